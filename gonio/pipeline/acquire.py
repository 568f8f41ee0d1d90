"""Acquisition through the instruments, for every specification: a specification's rate
programme (its ``acquisition`` hook, run by :mod:`gonio.instruments.rate_acquire`) or its own
programme on its own instruments (its ``acquire`` hook), chosen by the protocol. Nothing here
names a specification; ``gonio acquire`` and the records' worker both call :func:`acquire`.
"""

from __future__ import annotations

from pathlib import Path

from gonio.errors import GonioError
from gonio.specs import DEFAULT_KEY, get

#: The instrument roles a bench may have (VISA resource strings by role).
ROLES = ("table", "gyro", "chamber", "supply")


def acquiring_spec(protocol: str | Path, spec_key: str | None = None):
    """The specification the protocol file names (``[protocol] spec``), else ``spec_key``,
    else the default one (:data:`gonio.specs.DEFAULT_KEY`)."""
    from gonio.formats.toml import read_toml
    from gonio.resources import resolve

    sec = read_toml(resolve(protocol, kind="protocol")).get("protocol", {})
    key = sec.get("spec") if isinstance(sec, dict) else None
    key = key if isinstance(key, str) and key else spec_key
    spec = get(key or DEFAULT_KEY)
    if spec.acquisition is None and spec.acquire is None:
        raise GonioError(f"protocol {protocol}: gonio acquire does not run {spec.key} programmes "
                         "yet (the specification has no acquisition hook)")
    return spec


def acquire(protocol: str | Path, resources: dict[str, str | None], out: str | Path, *,
            spec_key: str | None = None, metadata: dict | None = None, resume: bool = False,
            timeout_s: float = 10.0, prompt=input):
    """Run the protocol's programme on the instruments at ``resources`` (by role:
    :data:`ROLES`); write ``out``/``readings.csv`` and ``out``/``io.log``. Returns the
    :class:`~gonio.instruments.run.AcquisitionResult`."""
    unknown = sorted(set(resources) - set(ROLES))
    if unknown:
        raise GonioError(f"unknown instrument role(s) {', '.join(unknown)}; expected "
                         f"{', '.join(ROLES)}")
    spec = acquiring_spec(protocol, spec_key)
    if spec.acquisition is None:
        return spec.acquire(str(protocol), dict(resources), out, metadata=dict(metadata or {}),
                            resume=resume, timeout_s=timeout_s, prompt=prompt)
    from gonio.instruments.rate_acquire import acquire_rate

    prog = spec.acquisition(str(protocol), dict(metadata or {}))
    return acquire_rate(prog.segments, prog.metadata, resources, out, resume=resume,
                        timeout_s=timeout_s,
                        prompt=prompt)
