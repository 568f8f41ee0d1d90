"""where a calibration was performed, as the DCC's category (dcc:performanceLocation:
laboratory, customer, laboratoryBranch, customerBranch, other), beside the place as text

Revision ID: 0006
Revises: 0005
Create Date: 2026-11-29 11:30:00
"""
from alembic import op
import sqlalchemy as sa


revision = '0006'
down_revision = '0005'
branch_labels = None
depends_on = None


def upgrade() -> None:
    op.add_column('calibrations', sa.Column('location', sa.String(length=16),
                                            nullable=False, server_default='laboratory'))


def downgrade() -> None:
    with op.batch_alter_table('calibrations', schema=None) as batch_op:
        batch_op.drop_column('location')
