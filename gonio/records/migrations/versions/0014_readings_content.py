"""a stored readings file's content digest (table ``readings_contents``,
:func:`gonio.formats.content.content_sha256`): readings that differ from another
calibration's only in how they are written (a newline, line ends, metadata lines, the order of
rows or columns, a number's spelling) are the same measurement, refused as such by
:func:`gonio.records.services.check_readings_unused`. Every calibration's readings are
digested from the stored files when the blob store is known (:func:`gonio.records.db.migrate`'s
``blob_root``), else when first compared. Insert-only, as ``blobs``: triggers refuse UPDATE
and DELETE.

Revision ID: 0014
Revises: 0013
Create Date: 2026-12-05 02:30:00
"""
from alembic import context, op
import sqlalchemy as sa


revision = '0014'
down_revision = '0013'
branch_labels = None
depends_on = None

#: why a content digest is never changed: it is a function of the stored file's bytes
WHY = 'a stored file is never changed'


def upgrade() -> None:
    op.create_table(
        'readings_contents',
        sa.Column('sha256', sa.String(length=64), nullable=False),
        sa.Column('content_sha256', sa.String(length=64), nullable=False),
        sa.ForeignKeyConstraint(['sha256'], ['blobs.sha256'], ),
        sa.PrimaryKeyConstraint('sha256'))
    op.create_index(op.f('ix_readings_contents_content_sha256'), 'readings_contents',
                    ['content_sha256'], unique=False)
    dialect = op.get_bind().dialect.name
    for verb in ("UPDATE", "DELETE"):
        name = f"readings_contents_no_{verb.lower()}"
        if dialect == "postgresql":
            op.execute(f"CREATE TRIGGER {name} BEFORE {verb} ON readings_contents FOR EACH ROW "
                       f"EXECUTE FUNCTION gonio_refuse('{WHY}')")
        else:
            op.execute(f"CREATE TRIGGER {name} BEFORE {verb} ON readings_contents "
                       f"BEGIN SELECT RAISE(ABORT, '{WHY}'); END")
    root = context.config.attributes.get("blob_root")
    if root is not None:
        backfill(op.get_bind(), root)


def backfill(bind, root) -> int:
    """The content digest of every calibration's readings file present in ``root``;
    returns the files digested."""
    from gonio.records.blobs import readings_content

    rc = sa.table('readings_contents', sa.column('sha256'), sa.column('content_sha256'))
    cals = sa.table('calibrations', sa.column('readings_sha256'))
    shas = sorted({r[0] for r in bind.execute(sa.select(cals.c.readings_sha256))})
    done = [{"sha256": sha, "content_sha256": d} for sha in shas
            if (d := readings_content(root, sha)) is not None]
    if done:
        bind.execute(rc.insert(), done)
    return len(done)


def downgrade() -> None:
    dialect = op.get_bind().dialect.name
    for verb in ("update", "delete"):
        op.execute(f"DROP TRIGGER IF EXISTS readings_contents_no_{verb}"
                   + (" ON readings_contents" if dialect == "postgresql" else ""))
    op.drop_index(op.f('ix_readings_contents_content_sha256'), table_name='readings_contents')
    op.drop_table('readings_contents')
