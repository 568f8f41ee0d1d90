"""the sealed review: calibrations.reviewed_seal and approved_seal (the result's content hash
each signatory signed), amend_requested_by_id (an amendment is asked for by one person and
approved by another); certificates.seal_sha256, reviewed_by_id and min_people (what a
certificate was issued from and under)

Revision ID: 0003
Revises: 0002
Create Date: 2026-11-29 02:10:00
"""
from alembic import op
import sqlalchemy as sa


revision = '0003'
down_revision = '0002'
branch_labels = None
depends_on = None


def _add_user_ref(table: str, column: str) -> None:
    # added in place (no table copy: certificates are frozen by triggers and referred to)
    if op.get_bind().dialect.name == 'sqlite':
        op.execute(f'ALTER TABLE {table} ADD COLUMN {column} INTEGER REFERENCES users (id)')
    else:
        op.add_column(table, sa.Column(column, sa.Integer(), nullable=True))
        op.create_foreign_key(f'fk_{table}_{column}_users', table, 'users', [column], ['id'])


def upgrade() -> None:
    for name in ('reviewed_seal', 'approved_seal'):
        op.add_column('calibrations', sa.Column(name, sa.String(length=64), nullable=False,
                                                server_default=''))
    _add_user_ref('calibrations', 'amend_requested_by_id')
    op.add_column('certificates', sa.Column('seal_sha256', sa.String(length=64),
                                            nullable=True))
    _add_user_ref('certificates', 'reviewed_by_id')
    op.add_column('certificates', sa.Column('min_people', sa.Integer(), nullable=True))


def downgrade() -> None:
    with op.batch_alter_table('certificates', schema=None) as batch_op:
        for name in ('min_people', 'reviewed_by_id', 'seal_sha256'):
            batch_op.drop_column(name)
    with op.batch_alter_table('calibrations', schema=None) as batch_op:
        for name in ('amend_requested_by_id', 'approved_seal', 'reviewed_seal'):
            batch_op.drop_column(name)
