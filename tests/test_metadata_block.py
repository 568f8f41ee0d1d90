"""The one metadata-block parser the triad's readings and the optical static record share, and
the one reader of the files a readings file names (``# static_record:``,
``# thermal_readings:``)."""

from __future__ import annotations

import pytest

from gonio.errors import GonioError
from gonio.formats.metadata import metadata_block, named_files
from gonio.specs.ogam_draft.static_record import (format_static_record, named_inputs,
                                                   read_static_record)
from gonio.specs.triad_alignment.readings import named_inputs as triad_named_inputs


def test_a_static_record_with_a_key_given_twice_is_refused_naming_the_line(tmp_path):
    text = format_static_record([0.0, 1.0], [0, 5], nominal_scale_factor_counts_per_deg=2.0,
                                source="t")
    f = tmp_path / "rec.csv"
    f.write_text(text)
    assert list(read_static_record(f).angle_deg) == [0.0, 2.5]
    lines = text.splitlines(keepends=True)
    f.write_text(lines[0] + lines[2] + "".join(lines[1:]))     # the scale factor twice
    with pytest.raises(GonioError) as exc:
        read_static_record(f)
    assert exc.value.line == 4 and "given twice" in exc.value.message


def test_a_line_without_a_colon_is_refused():
    with pytest.raises(GonioError) as exc:
        metadata_block(["# format: x", "# just words", "a,b"], "r.csv")
    assert exc.value.line == 2


@pytest.mark.parametrize("reader, key", [(named_inputs, "static_record"),
                                         (triad_named_inputs, "thermal_readings")])
def test_named_files_read_the_same_way_for_both_specifications(tmp_path, reader, key):
    f = tmp_path / "readings.csv"
    f.write_text("\ufeff# format: x\n\n# " + key + ": sub/rec.csv\na,b\n# " + key
                 + ": not/metadata.csv\n")
    assert reader(f) == [tmp_path / "sub" / "rec.csv"] == named_files(f, key)
    f.write_bytes(b"PAR1\x00\x01binary")                       # a stream names nothing
    assert reader(f) == []
    assert reader(tmp_path / "missing.csv") == []
