"""the laboratory's register of its rotary tables' calibrations (table_calibrations: the file
by SHA-256, the table, valid from / due on, who registered it), and the one a calibration used
(calibrations.table_calibration_id)

Revision ID: 0009
Revises: 0008
Create Date: 2026-12-01 05:20:00
"""
from alembic import op
import sqlalchemy as sa


revision = '0009'
down_revision = '0008'
branch_labels = None
depends_on = None


def upgrade() -> None:
    op.create_table('table_calibrations',
    sa.Column('id', sa.Integer(), nullable=False),
    sa.Column('standard_id', sa.Integer(), nullable=False),
    sa.Column('sha256', sa.String(length=64), nullable=False),
    sa.Column('name', sa.String(length=255), nullable=False),
    sa.Column('certificate', sa.String(length=200), nullable=False),
    sa.Column('valid_from', sa.Date(), nullable=False),
    sa.Column('due_on', sa.Date(), nullable=False),
    sa.Column('registered_by_id', sa.Integer(), nullable=True),
    sa.Column('registered_at', sa.DateTime(), nullable=False),
    sa.ForeignKeyConstraint(['registered_by_id'], ['users.id'], ),
    sa.ForeignKeyConstraint(['sha256'], ['blobs.sha256'], ),
    sa.ForeignKeyConstraint(['standard_id'], ['standards.id'], ),
    sa.PrimaryKeyConstraint('id'),
    sa.UniqueConstraint('standard_id', 'sha256'),
    sa.UniqueConstraint('standard_id', 'valid_from')
    )
    op.create_index('ix_table_calibrations_standard_id', 'table_calibrations', ['standard_id'],
                    unique=False)
    _freeze()
    # a nullable column with a reference: SQLite adds it in place with its REFERENCES
    # clause (Alembic would rebuild the table; SQLite allows it on a column whose default is
    # NULL), PostgreSQL as a column and a named constraint
    if op.get_bind().dialect.name == 'sqlite':
        op.execute('ALTER TABLE calibrations ADD COLUMN table_calibration_id INTEGER '
                   'REFERENCES table_calibrations (id)')
    else:
        op.add_column('calibrations', sa.Column('table_calibration_id', sa.Integer(),
                                                nullable=True))
        op.create_foreign_key('calibrations_table_calibration_id_fkey', 'calibrations',
                              'table_calibrations', ['table_calibration_id'], ['id'])


#: why a registered table calibration is never changed: a calibration's result was corrected
#: by it (a correction is a new registration, which supersedes it from its own date)
WHY = 'a registered table calibration is never changed or removed'


def _freeze() -> None:
    """Triggers refusing UPDATE and DELETE on the register, as 0001's on the certificates
    (``gonio_refuse()`` exists on PostgreSQL since 0001)."""
    dialect = op.get_bind().dialect.name
    for verb in ("UPDATE", "DELETE"):
        name = f"table_calibrations_no_{verb.lower()}"
        if dialect == "postgresql":
            op.execute(f"CREATE TRIGGER {name} BEFORE {verb} ON table_calibrations FOR EACH ROW "
                       f"EXECUTE FUNCTION gonio_refuse('{WHY}')")
        else:
            op.execute(f"CREATE TRIGGER {name} BEFORE {verb} ON table_calibrations "
                       f"BEGIN SELECT RAISE(ABORT, '{WHY}'); END")


def downgrade() -> None:
    dialect = op.get_bind().dialect.name
    for verb in ("update", "delete"):
        op.execute(f"DROP TRIGGER IF EXISTS table_calibrations_no_{verb}"
                   + (" ON table_calibrations" if dialect == "postgresql" else ""))
    if op.get_bind().dialect.name != 'sqlite':
        op.drop_constraint('calibrations_table_calibration_id_fkey', 'calibrations',
                           type_='foreignkey')
    # SQLite drops the referencing column by rebuilding the table (copy, DROP TABLE, rename):
    # as SQLite's procedure for such a change says (lang_altertable.html, "other kinds of
    # table schema changes"), the caller runs it with foreign keys off (PRAGMA
    # foreign_keys=OFF outside the transaction; the rows other tables reference are dropped
    # and copied back) and checks them after (PRAGMA foreign_key_check)
    with op.batch_alter_table('calibrations', schema=None) as batch_op:
        batch_op.drop_column('table_calibration_id')
    op.drop_index('ix_table_calibrations_standard_id', table_name='table_calibrations')
    op.drop_table('table_calibrations')
