"""gonio — calibration of optical-gyro goniometers (RLG and FOG angle-measuring instruments).

Contents (one module per piece of physics or procedure):

=========================  ===================================================
``gonio.physics.earth``            Earth rate, local frame, axis directions, Sagnac
``gonio.physics.kinematics``       table motion profiles; tilted sensing axis
``gonio.protocol``         the draft's procedures as data (TOML), validated
``gonio.bench``            the virtual bench: table, instrument, session
``gonio.formats.readings``               readings and stream files (docs/formats.md)
``gonio.specs``            the registry: every procedure (items, budget, certificate) a plug-in
``gonio.physics.tilt``             Annex A.4.2 elliptic projection; rigid-body tilt
``gonio.analysis.noise``            Allan deviation and the gyro noise model
``gonio.specs.ogam_draft.equal_division``              equal-division averaging, rotary-table comparison
``gonio.report``           certificate and figures
``gonio.cli``              the ``gonio`` command (thin layer over the above)
=========================  ===================================================
"""

__version__ = "0.1.0"
