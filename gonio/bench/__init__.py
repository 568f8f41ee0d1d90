"""The virtual bench: a simulated RLG/FOG goniometer on a simulated precision rotary table.

``config``      bench, table and instrument parameters from TOML (``protocols/benches``)
``table``       the table's positioning error and axis geometry
``instrument``  the goniometer: Sagnac rate on a tilted axis, scale factor and its
                nonlinearity, bias, noise, quantisation, counter
``session``     runs a protocol on a bench → readings file, truth, optional stream
"""

from gonio.bench.config import Bench, InstrumentConfig, TableConfig, load_bench
from gonio.bench.session import SessionResult, run_session, write_session

__all__ = ["Bench", "InstrumentConfig", "TableConfig", "load_bench", "SessionResult",
           "run_session", "write_session"]
