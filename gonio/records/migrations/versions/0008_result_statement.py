"""a result row keeps how its stored results.json states the item (``stated``: "interval",
"value" or "none") and the interval's rounded ends, so the instrument's history figure draws
from the rows alone; existing rows are filled from their stored results.json when the blob
store is known (:func:`gonio.records.db.migrate`'s ``blob_root``), else left None (read then)

Revision ID: 0008
Revises: 0007
Create Date: 2026-11-29 17:40:00
"""
from alembic import context, op
import sqlalchemy as sa


revision = '0008'
down_revision = '0007'
branch_labels = None
depends_on = None


def upgrade() -> None:
    op.add_column('result_items', sa.Column('stated', sa.String(length=8), nullable=True))
    op.add_column('result_items', sa.Column('interval_low', sa.Float(), nullable=True))
    op.add_column('result_items', sa.Column('interval_high', sa.Float(), nullable=True))
    root = context.config.attributes.get("blob_root")
    if root is not None:
        backfill(op.get_bind(), root)


def backfill(bind, root) -> int:
    """The statement columns of every result row of a stored result, from that results.json
    (:func:`gonio.records.results.fill_stated`); returns the rows filled."""
    from gonio.records.results import fill_stated

    items = sa.table('result_items', sa.column('id'), sa.column('key'),
                     sa.column('calibration_id'), sa.column('stated'),
                     sa.column('interval_low'), sa.column('interval_high'))
    cals = sa.table('calibrations', sa.column('id'), sa.column('results_sha256'))
    rows = [dict(r) for r in bind.execute(
        sa.select(items.c.id, items.c.key, cals.c.results_sha256)
        .join(cals, items.c.calibration_id == cals.c.id)
        .where(cals.c.results_sha256.is_not(None)).order_by(items.c.id)).mappings()]
    filled = fill_stated(root, rows, lambda r: r["results_sha256"])
    done = [{"row_id": r["id"], "s": r["stated"], "lo": r["interval_low"],
             "hi": r["interval_high"]} for r in rows if r["stated"] is not None]
    if done:
        bind.execute(items.update().where(items.c.id == sa.bindparam("row_id"))
                     .values(stated=sa.bindparam("s"), interval_low=sa.bindparam("lo"),
                             interval_high=sa.bindparam("hi")), done)
    return filled


def downgrade() -> None:
    with op.batch_alter_table('result_items', schema=None) as batch_op:
        batch_op.drop_column('interval_high')
        batch_op.drop_column('interval_low')
        batch_op.drop_column('stated')
