"""The laboratory's records: instruments, calibrations, certificates and their history in a
database (SQLAlchemy 2 + Alembic; SQLite by default, PostgreSQL by URL). See docs/records.md.

Modules (each a documented Python API; ``gonio serve`` and ``gonio db`` are thin over them):

=================  ===========================================================================
``db``             :func:`~gonio.records.db.open_store`: open and migrate the database
``models``         the tables; audit trail, certificates and stored files frozen by triggers
``services``       the workflow: register, create_calibration, review, approve, amend,
                   history, propose_interval, due_instruments, …
``worker``         run a calibration in its own process; the server's Dispatcher
``compute``        the one call into gonio's pipeline (readings → results and certificate)
``results``        results.json (any shape gonio writes) → items (key, value, unit, U)
``interval``       recalibration intervals from the history (ILAC-G24)
``auth``           Argon2id passwords, login throttling, browser sessions
``blobs``          the content-addressed file store (SHA-256, never modified)
``backup``         backup and restore of everything as one ZIP archive
``importer``       command-line output folders into the records
``queries``        paginated reads for the pages
=================  ===========================================================================
"""
