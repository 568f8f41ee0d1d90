"""gonio — calibration of optical-gyro goniometers (RLG and FOG angle-measuring instruments).

Contents (one folder per stage of the data flow, docs/architecture.md):

=================================  ==================================================
``gonio.physics``                  Earth rate, Sagnac, kinematics, alignment
``gonio.formats``                  streams, metadata, rate readings, the laboratory file
``gonio.protocol``                 the rate programme the rate specifications share
``gonio.bench``                    the virtual rate-gyro bench
``gonio.analysis.noise``           Allan deviation and the gyro noise model
``gonio.result``                   the one result, its items, GUM budget and item loop
``gonio.specs``                    the registry: every procedure (items, budget, certificate) a plug-in,
                                   each in its own package beside it (what only it uses inside)
``gonio.kit``                      the public plug-in kit every procedure uses
``gonio.report``                   certificate and figures
``gonio.cli``                      the ``gonio`` command (thin layer over the above)
=================================  ==================================================
"""

__version__ = "0.1.0"
