"""where a calibration's environment came from: entered by a person, or taken from the
readings file's metadata (attached to a calibration after it was put in, and stated so)

Revision ID: 0005
Revises: 0004
Create Date: 2026-11-29 08:30:00
"""
from alembic import op
import sqlalchemy as sa


revision = '0005'
down_revision = '0004'
branch_labels = None
depends_on = None


def upgrade() -> None:
    op.add_column('calibrations', sa.Column('environment_from', sa.String(length=16),
                                            nullable=False, server_default=''))


def downgrade() -> None:
    with op.batch_alter_table('calibrations', schema=None) as batch_op:
        batch_op.drop_column('environment_from')
