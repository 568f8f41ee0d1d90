"""the stream a readings file was reduced from (``readings_contents.source_sha256``, the
stream's SHA-256 as ``gonio reduce`` names it: ``# source_stream_sha256``), so that a stream
and its reduced readings are one measurement (:func:`gonio.records.services.readings_used_by`);
and the readings' content digest, second form (:data:`gonio.formats.content.VERSION` v2): an
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
import sqlalchemy as sa


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
    _empty()
    op.add_column('readings_contents',
                  sa.Column('source_sha256', sa.String(length=64), nullable=True))
    op.create_index(op.f('ix_readings_contents_source_sha256'), 'readings_contents',
                    ['source_sha256'], unique=False)
    root = context.config.attributes.get("blob_root")
    if root is not None:
        backfill(op.get_bind(), root)


def backfill(bind, root) -> int:
    """The content digest and source stream of every calibration's readings file present
    in ``root``; returns the files digested."""
    from gonio.records.blobs import content_rows

    rc = sa.table('readings_contents', sa.column('sha256'), sa.column('content_sha256'),
                  sa.column('source_sha256'))
    cals = sa.table('calibrations', sa.column('readings_sha256'))
    shas = sorted({r[0] for r in bind.execute(sa.select(cals.c.readings_sha256))})
    done = content_rows(root, shas)
    if done:
        bind.execute(rc.insert(), done)
    return len(done)


def downgrade() -> None:
    # the first form is no longer computed: the older code digests each file again when
    # it first compares it
    _empty()
    op.drop_index(op.f('ix_readings_contents_source_sha256'), table_name='readings_contents')
    op.execute("ALTER TABLE readings_contents DROP COLUMN source_sha256")
