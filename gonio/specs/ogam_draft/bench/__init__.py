"""The optical draft's virtual bench: a simulated RLG/FOG goniometer on a simulated precision
rotary table.

``config``      bench, table and instrument parameters from TOML (``protocols/benches``)
``instrument``  the goniometer: Sagnac rate on a tilted axis, scale factor and its
                nonlinearity, bias, noise, quantisation, counter
``session``     runs a protocol on a bench → readings file, truth, optional stream

Only the specification's simulation modules (``simulate``, ``truth``, ``study``), its served
bench (``served``), its demo (``outputs``) and the planning of its coupling budget line
(``budget_extra``) import it; calibrating a laboratory's file does not.
"""

from gonio.specs.ogam_draft.bench.config import Bench, InstrumentConfig, TableConfig, load_bench
from gonio.specs.ogam_draft.bench.session import SessionResult, run_session, write_session

__all__ = ["Bench", "InstrumentConfig", "TableConfig", "load_bench", "SessionResult",
           "run_session", "write_session"]
