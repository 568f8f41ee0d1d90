"""Alembic environment for gonio's records, run programmatically by
:func:`gonio.records.db.migrate` (the connection comes in ``config.attributes``).
Importing this module outside Alembic (a doctest collector) does nothing."""

from alembic import context

from gonio.records.models import Base


def run(config) -> None:
    """Run the migrations on the connection handed over by ``gonio.records.db``."""
    connection = config.attributes["connection"]
    context.configure(connection=connection, target_metadata=Base.metadata,
                      render_as_batch=connection.dialect.name == "sqlite")
    with context.begin_transaction():
        context.run_migrations()


try:
    _config = context.config
except (NameError, AttributeError):  # imported outside Alembic: nothing to run
    _config = None
if _config is not None:
    run(_config)
