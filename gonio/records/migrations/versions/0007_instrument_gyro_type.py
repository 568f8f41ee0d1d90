"""an instrument's optical-gyro type (rlg, fog or "" not stated), written into the laboratory
file its calibrations are computed with (``[instrument] gyro_type``)

Revision ID: 0007
Revises: 0006
Create Date: 2026-11-29 14:30:00
"""
from alembic import op
import sqlalchemy as sa


revision = '0007'
down_revision = '0006'
branch_labels = None
depends_on = None


def upgrade() -> None:
    op.add_column('instruments', sa.Column('gyro_type', sa.String(length=8),
                                           nullable=False, server_default=''))


def downgrade() -> None:
    with op.batch_alter_table('instruments', schema=None) as batch_op:
        batch_op.drop_column('gyro_type')
