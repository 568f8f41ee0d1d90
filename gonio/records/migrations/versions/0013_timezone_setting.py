"""the laboratory's time zone held by the store: the setting ``timezone`` gets this machine's
IANA zone name (:func:`gonio.records.models.machine_zone`; UTC where it cannot be determined)
where a store has none or an empty one, so that every process on the store reads one zone for
the records' "today" instead of its own local zone. A fresh store (``gonio db init``) gets it
too; a zone already set is kept.

Revision ID: 0013
Revises: 0012
Create Date: 2026-12-02 06:55:00
"""
from alembic import op
import sqlalchemy as sa


revision = '0013'
down_revision = '0012'
branch_labels = None
depends_on = None


def upgrade() -> None:
    from gonio.records.models import machine_zone

    conn = op.get_bind()
    st = sa.table('settings', sa.column('key', sa.String), sa.column('value', sa.Text))
    row = conn.execute(sa.select(st.c.value).where(st.c.key == 'timezone')).first()
    if row is None:
        conn.execute(st.insert().values(key='timezone', value=machine_zone()))
    elif not row[0]:
        conn.execute(st.update().where(st.c.key == 'timezone').values(value=machine_zone()))


def downgrade() -> None:
    pass
