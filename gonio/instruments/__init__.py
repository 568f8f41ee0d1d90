"""Instruments on a real (or served virtual) bench, through VISA.

``link``         a VISA link (PyVISA, ``@py`` backend) with a raw I/O log; the driver base
``table``        the rotary-table controller interface and its SCPI-style driver
``acquisition``  the goniometer's angle/rate acquisition module and its driver
``served``       the virtual bench served as those instruments (``gonio bench serve``)
``acquire``      a protocol's programme run on the instruments (``gonio acquire``)
``child``        a served bench or an acquisition started by a script, ended with it

docs/instruments.md says how a laboratory connects its own controller and module.
"""
