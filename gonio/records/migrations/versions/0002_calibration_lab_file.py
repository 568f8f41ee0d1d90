"""a calibration's laboratory file: calibrations.lab_sha256 (a stored file) and lab_name (its
name as uploaded, for display)

Revision ID: 0002
Revises: 0001
Create Date: 2026-11-26 13:45:00
"""
from alembic import op
import sqlalchemy as sa


revision = '0002'
down_revision = '0001'
branch_labels = None
depends_on = None


def upgrade() -> None:
    # added in place (no table copy: other tables refer to calibrations); SQLite takes the
    # reference in ADD COLUMN itself, PostgreSQL as a constraint
    op.add_column('calibrations', sa.Column('lab_name', sa.String(length=255), nullable=False,
                                            server_default=''))
    if op.get_bind().dialect.name == 'sqlite':
        op.execute('ALTER TABLE calibrations ADD COLUMN lab_sha256 VARCHAR(64) '
                   'REFERENCES blobs (sha256)')
    else:
        op.add_column('calibrations', sa.Column('lab_sha256', sa.String(length=64),
                                                nullable=True))
        op.create_foreign_key('fk_calibrations_lab_sha256_blobs', 'calibrations', 'blobs',
                              ['lab_sha256'], ['sha256'])


def downgrade() -> None:
    with op.batch_alter_table('calibrations', schema=None) as batch_op:
        batch_op.drop_column('lab_sha256')
        batch_op.drop_column('lab_name')
