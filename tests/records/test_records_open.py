"""Opening the records: Alembic runs only when the database is behind the shipped
migrations (gonio serve and every ``gonio db`` command open the store at start-up)."""

from __future__ import annotations

import subprocess
import sys

from gonio.records.db import MIGRATIONS, at_head, head_revision, migrate, open_store


def test_head_revision_is_alembics_head():
    from alembic.config import Config
    from alembic.script import ScriptDirectory

    cfg = Config()
    cfg.set_main_option("script_location", str(MIGRATIONS))
    assert head_revision() == ScriptDirectory.from_config(cfg).get_current_head()


def test_up_to_date_database_opens_without_alembic(tmp_path):
    store = open_store(None, tmp_path / "data")          # created: migrated to the head
    assert at_head(store.engine)
    store.close()
    code = ("import sys; from gonio.records.db import open_store; "
            f"s = open_store(None, {str(tmp_path / 'data')!r}); "
            "print('alembic' in sys.modules); s.close()")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout.split()
    assert out == ["False"]


def test_database_behind_the_head_is_migrated(tmp_path):
    store = open_store(None, tmp_path / "data", upgrade=False)
    assert not at_head(store.engine)                    # no alembic_version table yet
    migrate(store.engine, "0001")
    assert not at_head(store.engine)
    store.close()
    store = open_store(None, tmp_path / "data")
    assert at_head(store.engine)
    store.close()
