"""``gonio eda READINGS``: equal-division averaging of a readings file (IEC 62047-20 Annex A.3).

Reads the ``equal_division`` rows of a readings file, separates the table's
positioning error from the goniometer's error (:func:`gonio.eda.equal_division_analysis`)
and prints both with their standard uncertainties, the residual standard
deviation, the full-turn closure check and the harmonic transfer table.

The file is read with pandas here, not with :func:`gonio.io.read_readings`:
that reader treats (test, series, round, rate, orientation) as the key of one
reading, whereas an ``equal_division`` round holds ``m`` readings, one per
step (told apart by ``table_deg``).
"""

from __future__ import annotations

import io
import json
from pathlib import Path

import numpy as np
import pandas as pd

from gonio.atomic import write_bytes
from gonio.eda import EdaResult, eda_matrix_from_readings, equal_division_analysis
from gonio.errors import GonioError


from gonio.cli.checks import int_range, json_safe


def register(subparsers) -> None:
    """Add the ``eda`` sub-command."""
    p = subparsers.add_parser(
        "eda", help="equal-division averaging: table and goniometer errors (IEC 62047-20 A.3)",
        description="Separate a rotary table's positioning error from the goniometer's own "
                    "error with equal-division averaging (IEC 62047-20 Annex A.3).")
    p.add_argument("readings", metavar="READINGS", help="readings CSV with equal_division rows")
    p.add_argument("--starts", type=int_range(1, 10000), default=None, metavar="N",
                   help="number of starts n (required when the file has no start_deg column; "
                        "checked against the file otherwise)")
    p.add_argument("--gauge", choices=("closure", "zero"), default="closure",
                   help="table-error convention: sum zero over the circle, or zero at 0°")
    p.add_argument("--noise", choices=("random_walk", "white"), default="random_walk",
                   help="reading-error model: random_walk (a gyro's angle random walk from each "
                        "zeroing, the default) or white (independent readings)")
    p.add_argument("--json", action="store_true", help="print the result as JSON")
    p.add_argument("--plot", metavar="FILE", default=None,
                   help="write a figure (PNG/PDF/SVG by suffix) of both error curves")
    p.set_defaults(func=run)


def read_eda_csv(path: str | Path) -> pd.DataFrame:
    """Read a readings CSV with pandas; ``#`` metadata lines at the top are skipped.

    The returned DataFrame's index is the file's 1-based line number of each
    row, so errors name the line; empty cells are NaN, values stay text.

    >>> import tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "r.csv"
    >>> _ = p.write_text("# serial: 7\\ntest,series,round,start_deg,table_deg,gyro_deg\\n"
    ...                  "equal_division,1,1,0,180,180.0001\\n")
    >>> df = read_eda_csv(p)
    >>> df.index.tolist(), df.loc[3, "gyro_deg"]
    ([3], '180.0001')
    """
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8-sig")
    except OSError as exc:
        raise GonioError(f"cannot read readings file: {exc.strerror}", file=path) from None
    except UnicodeDecodeError:
        raise GonioError("not UTF-8 text", file=path) from None
    lines = text.splitlines()
    skip = 0
    while skip < len(lines) and (not lines[skip].strip() or lines[skip].lstrip().startswith("#")):
        skip += 1
    if skip >= len(lines):
        raise GonioError("no header row", file=path)
    try:
        df = pd.read_csv(io.StringIO("\n".join(lines[skip:])), dtype=str,
                         skip_blank_lines=False, keep_default_na=False)
    except (pd.errors.ParserError, pd.errors.EmptyDataError) as exc:
        raise GonioError(f"not a CSV table: {exc}".splitlines()[0], file=path) from None
    df.columns = [c.strip() for c in df.columns]
    df.index = np.arange(len(df)) + skip + 2          # header is line skip+1
    df = df[~(df == "").all(axis=1)]                  # blank lines
    return df.replace("", np.nan)


def _text(res: EdaResult) -> str:
    out = [f"equal-division averaging (IEC 62047-20 Annex A.3): n = {res.n_starts} starts, "
           f"m = {res.m_points} points ({res.step_deg:g}° step), {res.repeats} repeat(s)",
           f"residual std {res.residual_std_arcsec:.4f}″, dof {res.dof}, gauge {res.gauge}, "
           f"unobservable table dimensions {res.unobservable_dim}", "",
           f"{'position':>10} {'table err':>10} {'u':>8}   {'turned':>8} {'gonio err':>10} {'u':>8}"]
    for i in range(res.m_points):
        out.append(f"{res.table_position_deg[i]:9.4f}° {res.table_error_arcsec[i]:9.4f}″ "
                   f"{res.table_u_arcsec[i]:7.4f}″   {res.gonio_angle_deg[i]:7.3f}° "
                   f"{res.gonio_error_arcsec[i]:9.4f}″ {res.gonio_u_arcsec[i]:7.4f}″")
    c = res.closure
    out += ["", f"closure: sum of table errors {c.table_sum_arcsec:.4f}″; full-turn goniometer "
                f"error {c.full_turn_arcsec:.4f}″ ± {c.u_full_turn_arcsec:.4f}″ (z = {c.z:.2f}, "
                f"{'consistent with 0' if c.consistent else 'NOT consistent with 0'})"]
    bad = res.harmonics[res.harmonics.table_status == "unobservable"].order.tolist()
    if bad:
        out.append("table harmonics not separable from the goniometer (multiples of n): "
                   + ", ".join(map(str, bad)))
    return "\n".join(out)


def plot_eda(res: EdaResult, path: str | Path) -> Path:
    """Figure of the table and goniometer error curves with 1-σ bars, written atomically.

    The format follows the suffix (png, pdf, svg); matplotlib's Agg backend.

    >>> import tempfile, pathlib
    >>> from gonio.eda import simulate_eda_matrix
    >>> sim = simulate_eda_matrix({1: 1.0}, {2: 0.2}, 8, 8, 1, 0.05, 0)
    >>> res = equal_division_analysis(sim.D_arcsec, sim.start_deg, sim.step_deg)
    >>> out = plot_eda(res, pathlib.Path(tempfile.mkdtemp()) / "eda.svg")
    >>> out.read_text()[:5]
    '<?xml'
    """
    from matplotlib.figure import Figure

    from gonio.atomic import save_figure

    fig = Figure(figsize=(7, 6), constrained_layout=True)
    a1, a2 = fig.subplots(2, 1)
    a1.errorbar(res.table_position_deg, res.table_error_arcsec, yerr=res.table_u_arcsec,
                fmt="o-", capsize=3)
    a1.set(xlabel="table position / °", ylabel="table error / ″",
           title=f"rotary table (gauge: {res.gauge})")
    a2.errorbar(res.gonio_angle_deg, res.gonio_error_arcsec, yerr=res.gonio_u_arcsec,
                fmt="s-", capsize=3, color="C1")
    a2.set(xlabel="angle turned since zeroing / °", ylabel="goniometer error / ″",
           title="goniometer")
    for a in (a1, a2):
        a.axhline(0, color="0.6", lw=0.8)
        a.grid(alpha=0.3)
    return save_figure(fig, path)


def run(args) -> int:
    """Run ``gonio eda``; returns the exit code."""
    from gonio.atomic import check_output_file
    if args.plot is not None:
        check_output_file(args.plot, what="--plot", inputs=[args.readings])
    from gonio.errors import check_input_file
    check_input_file(args.readings, "readings file")
    df = read_eda_csv(args.readings)
    D, start, step = eda_matrix_from_readings(df, starts=args.starts, file=args.readings)
    res = equal_division_analysis(D, start, step, gauge=args.gauge, noise=args.noise)
    if args.plot:
        plot_eda(res, args.plot)
    if args.json:
        print(json.dumps(json_safe(res.to_dict()), indent=2, allow_nan=False))
    else:
        print(_text(res))
    return 0
