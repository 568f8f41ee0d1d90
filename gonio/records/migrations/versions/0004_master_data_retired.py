"""master data that can be retired: customers, instruments and standards get retired_on (a
retired instrument is not calibrated again, a retired standard not used again; their
history stays)

Revision ID: 0004
Revises: 0003
Create Date: 2026-11-29 02:40:00
"""
from alembic import op
import sqlalchemy as sa


revision = '0004'
down_revision = '0003'
branch_labels = None
depends_on = None

TABLES = ('customers', 'instruments', 'standards')


def upgrade() -> None:
    for table in TABLES:
        op.add_column(table, sa.Column('retired_on', sa.Date(), nullable=True))


def downgrade() -> None:
    for table in TABLES:
        with op.batch_alter_table(table, schema=None) as batch_op:
            batch_op.drop_column('retired_on')
