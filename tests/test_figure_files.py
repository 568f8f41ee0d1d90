"""Figures written to files: deterministic bytes, formats by suffix, no backend switch."""

import subprocess
import sys

import pytest
from matplotlib.figure import Figure

from gonio.errors import GonioError
from gonio.report.figure_files import figure_bytes, save_figure


def _fig():
    fig = Figure(figsize=(3, 2))
    ax = fig.add_subplot()
    ax.plot([0, 1, 2], [1, 3, 2], label="a")
    ax.legend()
    return fig


@pytest.mark.parametrize("fmt", ["png", "svg", "pdf"])
def test_same_figure_same_bytes(fmt, tmp_path):
    a = save_figure(_fig(), tmp_path / f"a.{fmt}").read_bytes()
    b = save_figure(_fig(), tmp_path / f"b.{fmt}").read_bytes()
    assert a == b and len(a) > 500


def test_pdf_and_svg_carry_no_date():
    assert b"CreationDate" not in figure_bytes(_fig(), "pdf")
    assert b"<dc:date>" not in figure_bytes(_fig(), "svg")


def test_unknown_suffix_is_one_line_error(tmp_path):
    with pytest.raises(GonioError, match=r"x\.jpg: cannot write a figure of type '\.jpg'"):
        save_figure(_fig(), tmp_path / "x.jpg")
    assert not (tmp_path / "x.jpg").exists()


def test_importing_the_report_leaves_the_backend_alone():
    code = ("import matplotlib; matplotlib.use('svg'); import gonio.report.figure_files, "
            "gonio.specs.ogam_draft.pages; print(matplotlib.get_backend())")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "svg"


def test_eda_plot_is_byte_stable(tmp_path):
    from gonio.cli import main
    from gonio.specs.ogam_draft.equal_division import simulate_eda_matrix
    sim = simulate_eda_matrix({1: 1.0, 3: 0.4}, {2: 0.2}, 8, 8, 1, 0.05, 0)
    lines = ["test,series,round,start_deg,table_deg,time_s,gyro_deg"]
    for k, x0 in enumerate(sim.start_deg):
        for j in range(1, 9):
            lines.append(f"equal_division,1,{k + 1},{x0:g},{j * 45:g},{10 * j},"
                         f"{j * 45 + sim.D_arcsec[0, k, j - 1] / 3600.0:.9f}")
    f = tmp_path / "r.csv"
    f.write_text("\n".join(lines) + "\n")
    for name in ("a.svg", "b.svg"):
        assert main(["eda", str(f), "--plot", str(tmp_path / name)]) == 0
    assert (tmp_path / "a.svg").read_bytes() == (tmp_path / "b.svg").read_bytes()
