"""JJF 1535-2015 on the virtual bench: run the protocol's programme and attach the truth.

The simulation side of the specification (it imports :mod:`gonio.bench`); calibrating a
laboratory's file never imports this module.
"""

from __future__ import annotations

from gonio.bench.rate_session import run_rate_session
from gonio.specs.jjf1535.protocol import KEY, JJFProtocol, load_protocol, null_output, plan
from gonio.specs.jjf1535.truth import truth as _truth


def simulate(bench, protocol=None, seed: int = 0, *, noise: bool = True):
    """Run the protocol's programme on a rate bench: (RateSessionResult with metadata, truth)."""
    proto = protocol if isinstance(protocol, JJFProtocol) else load_protocol(protocol or KEY)
    b = bench if noise else bench.without_noise()
    g, eq = b.gyro, b.equipment
    md = {"spec": KEY, "protocol": proto.path.stem if proto.path else KEY, "bench": b.name,
          "seed": seed, "noise": "on" if noise else "off", "instrument": g.name, "model": g.model,
          "serial": g.serial, "manufacturer": g.manufacturer, "output_unit": g.output_unit,
          "nominal_scale_factor": repr(g.scale_factor),
          "null_output": repr(null_output(proto, b)), "latitude_deg": repr(b.latitude_deg),
          "room_temperature_c": repr(proto["protocol"]["room_temperature_c"]),
          "supply_nominal_v": repr(g.supply_nominal_v),
          "rate_table_u_rel": repr(eq.rate_table_u_rel),
          "rate_table_ripple_rel": repr(eq.rate_table.ripple_rel),
          "acquisition_u_rel": repr(eq.acquisition_u_rel), "chamber_deviation_bound_c": "2.0",
          "chamber_uniformity_c": repr(eq.chamber.uniformity_c),
          "table": "rate table, two-axis position table, angular vibration table, chamber "
                   "(virtual)"}
    if eq.rate_table_u_rel is None:      # no certificate u: the budgets read Table 2's bound
        del md["rate_table_u_rel"]
    res = run_rate_session(plan(proto, b), b, seed,
                           room_temperature_c=proto["protocol"]["room_temperature_c"],
                           metadata=md, noise=noise)
    res.truth["items"] = _truth(b, proto)
    return res
