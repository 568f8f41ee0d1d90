"""Bench, table and instrument parameters, loaded from TOML and validated.

A bench file (``protocols/benches/rlg.toml``, ``fog.toml``) has sections
``bench`` (name, table file, simulation rate), ``site`` (latitude), ``chamber``
(its temperature's deviation from the protocol's reference, draft Table 2) and
``instrument`` (with its scale-factor and bias temperature coefficients); it names a
table file (``table-precision.toml``) holding the ``table`` section. Every key is checked: unknown keys, wrong types and
impossible values are a :class:`~gonio.errors.GonioError` naming file and key.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field, replace
from pathlib import Path

from gonio.errors import GonioError
from gonio.units import ARCSEC_PER_DEG
from gonio.resources import resolve
from gonio.formats.toml import Field, non_negative, positive, read_toml, validate_table


@dataclass(frozen=True)
class Harmonic:
    """One periodic term a·sin(order·x + phase), amplitude in arcsec."""

    order: int
    amplitude_arcsec: float
    phase_deg: float = 0.0


@dataclass(frozen=True)
class TableConfig:
    """A precision rotary table (draft Table 1)."""

    name: str = "error-free table"
    mpe_arcsec: float = 0.1
    accel_dps2: float = 60.0
    rate_error_rel: float = 0.0
    wobble_arcsec: float = 0.0
    wobble_phase_deg: float = 0.0
    axis_setup_error_deg: float = 0.0
    axis_setup_azimuth_deg: float = 0.0
    positioning_random_arcsec: float = 0.0
    positioning_harmonics: tuple[Harmonic, ...] = ()
    max_rate_dps: float = 300.0

    def error_bound_arcsec(self) -> float:
        """Σ|a_h| + 3σ: a bound on |indicated − true| for comparison with the MPE."""
        return sum(abs(h.amplitude_arcsec) for h in self.positioning_harmonics) \
            + 3.0 * self.positioning_random_arcsec


@dataclass(frozen=True)
class InstrumentConfig:
    """An optical-gyro goniometer (RLG or FOG) with pulse output."""

    type: str = "rlg"
    name: str = "goniometer"
    manufacturer: str = ""
    serial: str = ""
    nominal_scale_factor_counts_per_deg: float = 76434.87
    scale_factor_error_ppm: float = 0.0
    sf_rate_quadratic_ppm: float = 0.0
    sf_lowrate_ppm: float = 0.0
    sf_lowrate_scale_dps: float = 1.0
    position_harmonics: tuple[Harmonic, ...] = ()
    tilt_deg: float = 0.0
    tilt_azimuth_deg: float = 0.0
    bias_dph: float = 0.0
    warmup_drift_dph: float = 0.0
    warmup_tau_s: float = 1200.0
    arw_dpsh: float = 0.0
    bias_instability_dph: float = 0.0
    bias_instability_tau_s: float = 300.0
    rrw_dphsh: float = 0.0
    quantisation: bool = True
    quantisation_dither: bool = False
    counter_bits: int = 64
    counter_signed: bool = True
    integration: str = "exact"
    #: The rate at which the instrument itself samples and integrates its rate (a FOG's
    #: ``"rectangle"`` integration), Hz; 0: the simulation's rate. A simulation coarser
    #: than it (a coverage study at 100 Hz of a 1 kHz FOG) does not coarsen the
    #: instrument's integrator: it integrates the angle exactly (instrument.py).
    integration_rate_hz: float = 0.0
    sf_temperature_coeff_ppm_per_c: float = 0.0
    bias_temperature_coeff_dph_per_c: float = 0.0

    @property
    def true_scale_factor_counts_per_deg(self) -> float:
        """The instrument's true scale factor at zero rate: nominal·(1 + error)."""
        return self.nominal_scale_factor_counts_per_deg * (1.0 + 1e-6 * self.scale_factor_error_ppm)

    def at_temperature_deviation(self, deviation_c: float) -> "InstrumentConfig":
        """The same instrument ``deviation_c`` °C away from the reference temperature (the
        protocol's, draft Table 2): K·(1 + α_K ΔT) and bias + β ΔT, α_K
        (``sf_temperature_coeff_ppm_per_c``) and β (``bias_temperature_coeff_dph_per_c``)
        the first-order temperature coefficients of IEEE Std 647/952's gyro models; itself
        when ΔT = 0 (the reference instrument, bit for bit).

        >>> i = InstrumentConfig(nominal_scale_factor_counts_per_deg=1e6,
        ...                      sf_temperature_coeff_ppm_per_c=2.0, bias_dph=0.01,
        ...                      bias_temperature_coeff_dph_per_c=0.005)
        >>> j = i.at_temperature_deviation(-0.5)
        >>> round(j.true_scale_factor_counts_per_deg, 6), round(j.bias_dph, 6)
        (999999.0, 0.0075)
        >>> i.at_temperature_deviation(0.0) is i
        True
        """
        if not deviation_c:
            return self
        k_t = (1.0 + 1e-6 * self.scale_factor_error_ppm) \
            * (1.0 + 1e-6 * self.sf_temperature_coeff_ppm_per_c * deviation_c)
        return replace(self, scale_factor_error_ppm=(k_t - 1.0) * 1e6,
                       bias_dph=self.bias_dph + self.bias_temperature_coeff_dph_per_c * deviation_c)


@dataclass(frozen=True)
class Bench:
    """A virtual bench: instrument on a table at a site, simulated at ``sample_rate_hz``."""

    name: str
    instrument: InstrumentConfig
    table: TableConfig
    latitude_deg: float = 40.2
    longitude_deg: float = 116.2
    sample_rate_hz: float = 1000.0
    earth_rate: bool = True
    path: str = ""
    table_path: str = ""
    #: The chamber's temperature minus the protocol's reference (draft Table 2: (20 ± 1) °C).
    chamber_deviation_c: float = 0.0

    def at_chamber_temperature(self) -> "Bench":
        """The bench with its instrument at the chamber's temperature
        (:meth:`InstrumentConfig.at_temperature_deviation`); itself at the reference."""
        inst = self.instrument.at_temperature_deviation(self.chamber_deviation_c)
        return self if inst is self.instrument else replace(self, instrument=inst)

    def random_off(self) -> "Bench":
        """The same bench with every random term off (for truth's systematic deviations).

        Instrument noise (ARW, bias instability, rate random walk) and
        quantisation are switched off; the table's random positioning scatter is
        kept (its draws are the same), so the true angles are identical.
        """
        inst = replace(self.instrument, arw_dpsh=0.0, bias_instability_dph=0.0,
                       rrw_dphsh=0.0, quantisation=False)
        return replace(self, instrument=inst)

    def to_dict(self) -> dict:
        """Every parameter, for ``truth.json``.

        The bench and table files are given by name and SHA-256 of their bytes, never
        by the path as typed (same inputs, same bytes, from any working directory).
        """
        d = asdict(self)
        for key in ("path", "table_path"):
            d[key] = _file_id(d[key])
        return d


def _file_id(path: str) -> str:
    """``name sha256:<hex>`` of a file (empty when there is none)."""
    if not path:
        return ""
    from gonio.atomic import sha256_file

    try:
        digest = sha256_file(path)
    except OSError:
        return Path(path).name
    return f"{Path(path).name} sha256:{digest}"


#: Largest table/instrument error term accepted: one degree, in arc-seconds.
_ONE_DEG_ARCSEC: float = ARCSEC_PER_DEG


def _within(lo: float, hi: float):
    return lambda x: lo <= x <= hi


def check_counter(bench: "Bench", file=None) -> None:
    """Refuse a bench whose pulse counter could wrap more than half its range between samples.

    At the table's highest rate (``table.max_rate_dps``) the counter moves
    K·ω/f_s counts per sample (K the nominal scale factor with 1 % margin, f_s the
    sample rate); unwrapping a ``counter_bits`` counter is unambiguous only below
    2^(bits−1) counts per sample.
    """
    inst = bench.instrument
    per_sample = 1.01 * inst.nominal_scale_factor_counts_per_deg * bench.table.max_rate_dps \
        / bench.sample_rate_hz
    half = 2.0 ** (inst.counter_bits - 1)
    if per_sample >= half:
        raise GonioError(f"a {inst.counter_bits}-bit counter moves {per_sample:.0f} counts per "
                         f"sample at {bench.table.max_rate_dps:g} °/s and "
                         f"{bench.sample_rate_hz:g} Hz, more than half its range ({half:.0f}): "
                         "it would wrap undetectably; raise sample_rate_hz or counter_bits",
                         file=file, key="instrument.counter_bits")


_HARM = {"order": Field("int", check=_within(1, 1000), expect="an integer in [1, 1000]"),
         "amplitude_arcsec": Field("float", check=_within(-_ONE_DEG_ARCSEC, _ONE_DEG_ARCSEC),
                                   expect="within ±3600″"),
         "phase_deg": Field("float", 0.0)}
TABLE_SCHEMA = {
    "name": Field("str", "rotary table"),
    "mpe_arcsec": Field("float", 0.1, _within(1e-6, _ONE_DEG_ARCSEC), "in [1e-6, 3600]"),
    "accel_dps2": Field("float", 60.0, _within(1e-3, 1e5), "in [1e-3, 1e5] °/s²"),
    "max_rate_dps": Field("float", 300.0, _within(1e-3, 1e4), "in [1e-3, 1e4] °/s"),
    "rate_error_rel": Field("float", 0.0, lambda x: abs(x) < 0.01, "|x| < 0.01"),
    "wobble_arcsec": Field("float", 0.0, _within(0.0, _ONE_DEG_ARCSEC), "in [0, 3600]"),
    "wobble_phase_deg": Field("float", 0.0),
    "axis_setup_error_deg": Field("float", 0.0, lambda x: 0 <= x < 5, "0 ≤ x < 5"),
    "axis_setup_azimuth_deg": Field("float", 0.0),
    "positioning_random_arcsec": Field("float", 0.0, _within(0.0, _ONE_DEG_ARCSEC), "in [0, 3600]"),
    "positioning_harmonics": Field("table_list", [], schema=_HARM),
}
INSTRUMENT_SCHEMA = {
    "type": Field("str", "rlg", choices=("rlg", "fog")),
    "name": Field("str", "goniometer"),
    "manufacturer": Field("str", ""),
    "serial": Field("str", ""),
    "nominal_scale_factor_counts_per_deg": Field("float", check=_within(1e-3, 1e9),
                                                 expect="in [1e-3, 1e9]"),
    "scale_factor_error_ppm": Field("float", 0.0, _within(-1e5, 1e5), "within ±1e5 ppm"),
    "sf_rate_quadratic_ppm": Field("float", 0.0, _within(-1e5, 1e5), "within ±1e5 ppm"),
    "sf_lowrate_ppm": Field("float", 0.0, _within(-1e5, 1e5), "within ±1e5 ppm"),
    "sf_lowrate_scale_dps": Field("float", 1.0, _within(1e-6, 1e4), "in [1e-6, 1e4] °/s"),
    "position_harmonics": Field("table_list", [], schema=_HARM),
    "tilt_deg": Field("float", 0.0, lambda x: 0 <= x < 10, "0 ≤ tilt < 10"),
    "tilt_azimuth_deg": Field("float", 0.0),
    "bias_dph": Field("float", 0.0, _within(-1e4, 1e4), "within ±1e4 °/h"),
    "warmup_drift_dph": Field("float", 0.0, _within(-1e4, 1e4), "within ±1e4 °/h"),
    "warmup_tau_s": Field("float", 1200.0, _within(1e-3, 1e6), "in [1e-3, 1e6] s"),
    "arw_dpsh": Field("float", 0.0, _within(0.0, 100.0), "in [0, 100] °/√h"),
    "bias_instability_dph": Field("float", 0.0, _within(0.0, 1e4), "in [0, 1e4] °/h"),
    "bias_instability_tau_s": Field("float", 300.0, _within(1e-3, 1e6), "in [1e-3, 1e6] s"),
    "rrw_dphsh": Field("float", 0.0, _within(0.0, 1e4), "in [0, 1e4] °/h/√h"),
    "quantisation": Field("bool", True),
    "quantisation_dither": Field("bool", False),
    "counter_bits": Field("int", 64, choices=(16, 24, 32, 64)),
    "counter_signed": Field("bool", True),
    "integration": Field("str", "exact", choices=("exact", "rectangle")),
    "sf_temperature_coeff_ppm_per_c": Field("float", 0.0, _within(-1e4, 1e4),
                                            "within ±1e4 ppm/°C"),
    "bias_temperature_coeff_dph_per_c": Field("float", 0.0, _within(-1e3, 1e3),
                                              "within ±1e3 °/h/°C"),
}
BENCH_SCHEMA = {
    "bench": Field("table", schema={
        "name": Field("str"),
        "table": Field("str", "table-precision"),
        "sample_rate_hz": Field("float", 1000.0, lambda x: 1 <= x <= 100_000, "1–100000 Hz"),
        "earth_rate": Field("bool", True),
    }),
    "site": Field("table", {}, schema={
        "latitude_deg": Field("float", 40.2, lambda x: abs(x) <= 90, "within ±90"),
        "longitude_deg": Field("float", 0.0, lambda x: abs(x) <= 180, "within ±180"),
    }),
    "chamber": Field("table", {}, schema={
        "deviation_c": Field("float", 0.0, lambda x: abs(x) <= 50, "within ±50 °C"),
    }),
    "instrument": Field("table", schema=INSTRUMENT_SCHEMA),
    "table": Field("table", None, schema=TABLE_SCHEMA),
}


def _harmonics(rows) -> tuple[Harmonic, ...]:
    return tuple(Harmonic(r["order"], r["amplitude_arcsec"], r["phase_deg"]) for r in rows)


def table_from_dict(d: dict) -> TableConfig:
    """Build a :class:`TableConfig` from a validated ``table`` section."""
    d = dict(d)
    d["positioning_harmonics"] = _harmonics(d["positioning_harmonics"])
    return TableConfig(**d)


def load_table(path: str | Path) -> tuple[TableConfig, Path]:
    """Load a table file (a path or a built-in name such as ``table-precision``)."""
    file = resolve(path, "bench")
    raw = read_toml(file)
    if set(raw) != {"table"}:
        bad = sorted(set(raw) - {"table"}) or ["table"]
        raise GonioError("a table file holds exactly one [table] section", file=file, key=bad[0])
    return table_from_dict(validate_table(raw["table"], TABLE_SCHEMA, "table", file)), file


def load_bench(path: str | Path = "rlg", table: str | Path | None = None) -> Bench:
    """Load a bench file (path or built-in name ``rlg``/``fog``) and its table.

    >>> b = load_bench("rlg")
    >>> b.instrument.type, b.table.mpe_arcsec, round(b.table.error_bound_arcsec(), 3)
    ('rlg', 0.1, 0.085)
    """
    file = resolve(path, "bench")
    raw = validate_table(read_toml(file), BENCH_SCHEMA, "", file)
    inst = dict(raw["instrument"])
    inst["position_harmonics"] = _harmonics(inst["position_harmonics"])
    instrument = InstrumentConfig(**inst)
    if table is not None:
        tab, tfile = load_table(table)
    elif raw["table"] is not None:
        tab, tfile = table_from_dict(raw["table"]), file
    else:
        tname = raw["bench"]["table"]
        cand = file.parent / f"{tname}.toml"
        try:
            tab, tfile = load_table(cand if cand.is_file() else tname)
        except GonioError as exc:
            if exc.file is not None:        # the table file itself is bad: it names itself
                raise
            raise GonioError(exc.message, file=file, key="bench.table") from None
    bench = Bench(name=raw["bench"]["name"], instrument=instrument, table=tab,
                  latitude_deg=raw["site"]["latitude_deg"],
                  longitude_deg=raw["site"]["longitude_deg"],
                  sample_rate_hz=raw["bench"]["sample_rate_hz"],
                  earth_rate=raw["bench"]["earth_rate"], path=str(file), table_path=str(tfile),
                  chamber_deviation_c=float(raw["chamber"].get("deviation_c", 0.0)))
    check_counter(bench, file)
    return bench
