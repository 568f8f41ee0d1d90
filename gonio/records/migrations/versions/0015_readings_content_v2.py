"""the readings' content digest, second form (:data:`gonio.formats.content.VERSION` v2): an
integer cell kept whole (a 64-bit counter's counts no longer collapse to 15 digits, which made
two different streams one), a column with no value in any row no part of the data, lines split
where the readers split them. Every kept digest is of the first form and would never match a
new one: the table is emptied (its triggers set aside for that alone) and every calibration's
readings digested again from the stored files when the blob store is known, else when first
compared (:func:`gonio.records.services.readings_content_of`).

Revision ID: 0015
Revises: 0014
Create Date: 2026-12-05 09:30:00
"""
from alembic import context, op


revision = '0015'
down_revision = '0014'
branch_labels = None
depends_on = None

#: why a content digest is never changed (as migration 0014 states it)
WHY = 'a stored file is never changed'


def _empty() -> None:
    """Delete every kept digest, the no-delete trigger set aside for it and put back."""
    dialect = op.get_bind().dialect.name
    on = " ON readings_contents" if dialect == "postgresql" else ""
    op.execute(f"DROP TRIGGER IF EXISTS readings_contents_no_delete{on}")
    op.execute("DELETE FROM readings_contents")
    if dialect == "postgresql":
        op.execute("CREATE TRIGGER readings_contents_no_delete BEFORE DELETE ON "
                   f"readings_contents FOR EACH ROW EXECUTE FUNCTION gonio_refuse('{WHY}')")
    else:
        op.execute("CREATE TRIGGER readings_contents_no_delete BEFORE DELETE ON "
                   f"readings_contents BEGIN SELECT RAISE(ABORT, '{WHY}'); END")


def upgrade() -> None:
    import importlib

    _empty()
    root = context.config.attributes.get("blob_root")
    if root is not None:
        first = importlib.import_module(
            "gonio.records.migrations.versions.0014_readings_content")
        first.backfill(op.get_bind(), root)


def downgrade() -> None:
    # the first form is no longer computed: the older code digests each file again when
    # it first compares it
    _empty()
