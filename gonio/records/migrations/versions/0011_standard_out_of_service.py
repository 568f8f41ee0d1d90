"""a standard registered past its due date: the reason the person registering it stated
(``standards.out_of_service``; registered out of service: no calibration can use it until
its recalibration is recorded); "" for a standard registered in time. Registering one past
its due date without a reason is refused by the service
(:func:`gonio.records.services.add_standard`).

Revision ID: 0011
Revises: 0010
Create Date: 2026-12-01 15:45:00
"""
from alembic import op
import sqlalchemy as sa


revision = '0011'
down_revision = '0010'
branch_labels = None
depends_on = None


def upgrade() -> None:
    op.add_column('standards', sa.Column('out_of_service', sa.Text(), nullable=False,
                                         server_default=''))


def downgrade() -> None:
    with op.batch_alter_table('standards', schema=None) as batch_op:
        batch_op.drop_column('out_of_service')
