"""the environment as entered: ``calibrations.temperature_text`` and ``humidity_text`` keep the
digits the temperature and humidity were entered with ("20" or "20.0"), beside the numbers,
so that the laboratory file the records write for a calibration, its certificate, DCC and
the records' page state the same text (:func:`gonio.records.services.condition_digits`).
Rows recorded before keep the text they were printed with: the number to 6 significant
digits, as the records' page showed it ("20" for 20.0).

Revision ID: 0012
Revises: 0011
Create Date: 2026-12-01 20:10:00
"""
from alembic import op
import sqlalchemy as sa


revision = '0012'
down_revision = '0011'
branch_labels = None
depends_on = None


def _printed(x) -> str | None:
    """A number recorded before the text was kept, as the records' page printed it."""
    return None if x is None else f"{float(x):g}"


def upgrade() -> None:
    op.add_column('calibrations', sa.Column('temperature_text', sa.String(40), nullable=True))
    op.add_column('calibrations', sa.Column('humidity_text', sa.String(40), nullable=True))
    conn = op.get_bind()
    cal = sa.table('calibrations', sa.column('id', sa.Integer),
                   sa.column('temperature_c', sa.Float), sa.column('humidity_pct', sa.Float),
                   sa.column('temperature_text', sa.String),
                   sa.column('humidity_text', sa.String))
    rows = conn.execute(sa.select(cal.c.id, cal.c.temperature_c, cal.c.humidity_pct).where(
        sa.or_(cal.c.temperature_c.is_not(None), cal.c.humidity_pct.is_not(None)))).all()
    for cid, temp, hum in rows:
        conn.execute(cal.update().where(cal.c.id == cid).values(
            temperature_text=_printed(temp), humidity_text=_printed(hum)))


def downgrade() -> None:
    with op.batch_alter_table('calibrations', schema=None) as batch_op:
        batch_op.drop_column('humidity_text')
        batch_op.drop_column('temperature_text')
