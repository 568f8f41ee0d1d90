"""gonio — calibration of optical-gyro goniometers (RLG and FOG angle-measuring instruments).

Contents (one module per piece of physics or procedure):

=========================  ===================================================
``gonio.earth``            Earth rate, local frame, axis directions, Sagnac
``gonio.kinematics``       table motion profiles; tilted sensing axis
``gonio.protocol``         the draft's procedures as data (TOML), validated
``gonio.bench``            the virtual bench: table, instrument, session
``gonio.io``               readings and stream files (data-formats contract)
``gonio.characteristics``  the seven characteristics of draft clause 7
``gonio.tilt``             Annex A.4.2 elliptic projection; rigid-body tilt
``gonio.budget``           the Annex A uncertainty budget
``gonio.analysis.noise``   Allan deviation and the gyro noise model
``gonio.eda``              equal-division averaging, rotary-table comparison
``gonio.report``           certificate and figures
``gonio.cli``              the ``gonio`` command (thin layer over the above)
=========================  ===================================================
"""

__version__ = "0.1.0"
