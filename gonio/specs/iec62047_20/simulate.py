"""IEC 62047-20 on the virtual bench: run the protocol's programme and attach the truth.

The simulation side of the specification (it imports :mod:`gonio.bench`); calibrating a
laboratory's file never imports this module.
"""

from __future__ import annotations

from gonio.bench.rate_session import run_rate_session
from gonio.specs.iec62047_20.protocol import KEY, IECProtocol, load_protocol, plan, t_base
from gonio.specs.iec62047_20.truth import hysteresis_truth, truth


def simulate(bench, protocol=None, seed: int = 0, *, noise: bool = True):
    """Run the IEC programme on a rate bench: RateSessionResult with metadata and truth."""
    proto = protocol if isinstance(protocol, IECProtocol) else load_protocol(protocol or KEY)
    b = bench if noise else bench.without_noise()
    g, eq = b.gyro, b.equipment
    P = proto["protocol"]
    md = {"spec": KEY, "protocol": proto.path.stem if proto.path else KEY, "bench": b.name,
          "seed": seed, "noise": "on" if noise else "off", "instrument": g.name, "model": g.model,
          "serial": g.serial, "manufacturer": g.manufacturer, "output_unit": g.output_unit,
          "nominal_scale_factor": repr(g.scale_factor if P["nominal_scale_factor"] == "bench"
                                       else P["nominal_scale_factor"]),
          "null_output": repr(g.null_output if P["null_output"] == "bench" else P["null_output"]),
          "latitude_deg": repr(b.latitude_deg if P["latitude_deg"] == "bench" else P["latitude_deg"]),
          "room_temperature_c": repr(t_base(proto)), "supply_nominal_v": repr(g.supply_nominal_v),
          "rate_table_u_rel": repr(eq.rate_table_u_rel),
          "acquisition_u_rel": repr(eq.acquisition_u_rel),
          "chamber_deviation_bound_c": repr(eq.chamber_deviation_bound_c),
          "chamber_fluctuation_c": repr(eq.chamber.fluctuation_c),
          "chamber_uniformity_c": repr(eq.chamber.uniformity_c),
          "chamber_fluctuation_period_s": repr(eq.chamber.fluctuation_period_s),
          "ratiometric": "true" if g.ratiometric else "false"}
    if eq.rate_table_u_rel is None:      # no certificate u: the budgets read Table 2's bound
        del md["rate_table_u_rel"]
    res = run_rate_session(plan(proto, b), b, seed, room_temperature_c=20.0, metadata=md,
                           noise=noise)
    res.truth["items"] = truth(b, proto)
    # a single calibration measures K of its own power-up: the truth carries its scatter
    sf_seg = next((t for t in res.truth["segments"] if t["test"] == "scale_factor"), None)
    if sf_seg is not None and noise:
        eps = res.truth["power_cycles"][sf_seg["power_cycle"]]["scale_factor_scatter_rel"]
        items = res.truth["items"]
        items["scale_factor"]["value"] *= 1 + eps
        items["scale_factor"]["power_cycle_scatter_rel"] = eps
        items["initial_sf_variation"]["value"] = 100 * (items["scale_factor"]["value"]
                                                        - g.scale_factor) / g.scale_factor
    # 5.3.3.7: the true bias of every temperature visit (thermal lag included) from the session
    segs = [t for t in res.truth["segments"] if t["test"] == "bias_temperature"]
    if segs:
        kr = float(g.scale_factor_at(t_base(proto), g.supply_nominal_v)) / \
            res.truth["items"]["scale_factor"]["value"]
        h, d = hysteresis_truth([t["temperature_c"] for t in segs],
                                [t["bias_dps"] * kr for t in segs])
        res.truth["items"]["bias_hysteresis"] = {"value": h, "up_minus_down_dps": d,
                                                 "how": "5.3.3.7 on the session's true biases"}
    return res
