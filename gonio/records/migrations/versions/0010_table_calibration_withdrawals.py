"""a register entry withdrawn (table_calibration_withdrawals: the entry, the reason, who asked
and when, who approved it and when it took effect; frozen by triggers), and the register's
one-file-per-table and one-start-per-day rules moved from the database to the service, where
they hold among the entries not withdrawn (a withdrawn entry's file and day can be registered
again, rightly)

Revision ID: 0010
Revises: 0009
Create Date: 2026-12-01 08:40:00
"""
from alembic import op
import sqlalchemy as sa


revision = '0010'
down_revision = '0009'
branch_labels = None
depends_on = None

#: why a withdrawal is never changed: it is the record of when an entry stopped being in force
WHY = 'a table calibration withdrawal is never changed or removed'
#: 0009's reason, for the register's triggers made again on SQLite's rebuilt table
WHY_0009 = 'a registered table calibration is never changed or removed'
#: the register's rules 0009 kept in the database (column lists)
UNIQUE = (("standard_id", "valid_from"), ("standard_id", "sha256"))


def _columns():
    return [sa.Column('id', sa.Integer(), nullable=False),
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
            sa.PrimaryKeyConstraint('id')]


def _freeze(table: str, why: str) -> None:
    """Triggers refusing UPDATE and DELETE on ``table`` (``gonio_refuse()`` exists on
    PostgreSQL since 0001)."""
    dialect = op.get_bind().dialect.name
    for verb in ("UPDATE", "DELETE"):
        name = f"{table}_no_{verb.lower()}"
        if dialect == "postgresql":
            op.execute(f"CREATE TRIGGER {name} BEFORE {verb} ON {table} FOR EACH ROW "
                       f"EXECUTE FUNCTION gonio_refuse('{why}')")
        else:
            op.execute(f"CREATE TRIGGER {name} BEFORE {verb} ON {table} "
                       f"BEGIN SELECT RAISE(ABORT, '{why}'); END")


def _rebuild_sqlite(unique: bool) -> None:
    """SQLite keeps a table's UNIQUE constraints in its CREATE TABLE: the register is made
    again (a new table, the rows copied, the old one dropped, the new one renamed; its index
    and 0009's triggers made again), as SQLite's procedure for such a change says
    (lang_altertable.html): :func:`gonio.records.db.migrate` runs the migrations with
    foreign keys off and checks them after. DROP TABLE fires no DELETE trigger."""
    extra = [sa.UniqueConstraint(*cols) for cols in UNIQUE] if unique else []
    op.create_table('_table_calibrations_new', *_columns(), *extra)
    names = ", ".join(c.name for c in _columns() if isinstance(c, sa.Column))
    op.execute(f"INSERT INTO _table_calibrations_new ({names}) SELECT {names} "
               "FROM table_calibrations")
    op.execute("DROP TABLE table_calibrations")
    op.execute("ALTER TABLE _table_calibrations_new RENAME TO table_calibrations")
    op.create_index('ix_table_calibrations_standard_id', 'table_calibrations', ['standard_id'],
                    unique=False)
    _freeze("table_calibrations", WHY_0009)


def upgrade() -> None:
    bind = op.get_bind()
    if bind.dialect.name == 'sqlite':
        _rebuild_sqlite(unique=False)
    else:
        for uc in sa.inspect(bind).get_unique_constraints('table_calibrations'):
            if tuple(uc['column_names']) in UNIQUE:
                op.drop_constraint(uc['name'], 'table_calibrations', type_='unique')
    op.create_table('table_calibration_withdrawals',
    sa.Column('id', sa.Integer(), nullable=False),
    sa.Column('table_calibration_id', sa.Integer(), nullable=False),
    sa.Column('reason', sa.Text(), nullable=False),
    sa.Column('asked_by_id', sa.Integer(), nullable=True),
    sa.Column('asked_at', sa.DateTime(), nullable=False),
    sa.Column('withdrawn_by_id', sa.Integer(), nullable=True),
    sa.Column('withdrawn_at', sa.DateTime(), nullable=False),
    sa.ForeignKeyConstraint(['asked_by_id'], ['users.id'], ),
    sa.ForeignKeyConstraint(['table_calibration_id'], ['table_calibrations.id'], ),
    sa.ForeignKeyConstraint(['withdrawn_by_id'], ['users.id'], ),
    sa.PrimaryKeyConstraint('id'),
    sa.UniqueConstraint('table_calibration_id')
    )
    _freeze("table_calibration_withdrawals", WHY)


def downgrade() -> None:
    bind = op.get_bind()
    for cols in UNIQUE:          # the rows the 0009 rules would refuse: say which, change none
        twice = bind.execute(sa.text(
            f"SELECT {', '.join(cols)}, COUNT(*) FROM table_calibrations "
            f"GROUP BY {', '.join(cols)} HAVING COUNT(*) > 1")).fetchall()
        if twice:
            raise RuntimeError(
                f"cannot downgrade below 0010: the register holds {len(twice)} pair(s) of "
                f"entries with the same {' and '.join(cols)} (a withdrawn entry and the one "
                "registered in its place), which 0009's schema refuses")
    if bind.dialect.name == "postgresql":
        for verb in ("update", "delete"):
            op.execute(f"DROP TRIGGER IF EXISTS table_calibration_withdrawals_no_{verb} "
                       "ON table_calibration_withdrawals")
    op.drop_table('table_calibration_withdrawals')
    if bind.dialect.name == 'sqlite':
        _rebuild_sqlite(unique=True)
    else:
        for cols in UNIQUE:
            op.create_unique_constraint(f"table_calibrations_{'_'.join(cols)}_key",
                                        'table_calibrations', list(cols))
