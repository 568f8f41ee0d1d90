"""Acquisition through the instruments, for every specification: the goniometer's programme
(:mod:`gonio.instruments.acquire`) or a specification's rate programme (its ``acquisition``
hook, run by :mod:`gonio.instruments.rate_acquire`), chosen by the protocol. Nothing here
names a specification; ``gonio acquire`` and the records' worker both call :func:`acquire`.
"""

from __future__ import annotations

from pathlib import Path

from gonio.errors import GonioError
from gonio.specs import get

#: The instrument roles a bench may have (VISA resource strings by role).
ROLES = ("table", "gyro", "chamber", "supply")


def acquisition_hook(protocol: str | Path, spec_key: str | None = None):
    """The acquisition hook of the specification the protocol file names (``[protocol]
    spec``, else ``spec_key``); None: the goniometer's programme."""
    from gonio.formats.toml import read_toml
    from gonio.resources import resolve

    sec = read_toml(resolve(protocol, kind="protocol")).get("protocol", {})
    key = sec.get("spec") if isinstance(sec, dict) else None
    key = key if isinstance(key, str) and key else spec_key
    if not key:
        return None
    spec = get(key)
    if spec.acquisition is None and isinstance(sec, dict) and sec.get("spec"):
        raise GonioError(f"protocol {protocol}: gonio acquire does not run {key} programmes "
                         "yet (the specification has no acquisition hook)")
    return spec.acquisition


def acquire(protocol: str | Path, resources: dict[str, str | None], out: str | Path, *,
            spec_key: str | None = None, metadata: dict | None = None, resume: bool = False,
            timeout_s: float = 10.0, prompt=input):
    """Run the protocol's programme on the instruments at ``resources`` (by role:
    :data:`ROLES`); write ``out``/``readings.csv`` and ``out``/``io.log``. Returns the
    :class:`~gonio.instruments.acquire.AcquisitionResult`."""
    unknown = sorted(set(resources) - set(ROLES))
    if unknown:
        raise GonioError(f"unknown instrument role(s) {', '.join(unknown)}; expected "
                         f"{', '.join(ROLES)}")
    hook = acquisition_hook(protocol, spec_key)
    if hook is not None:
        from gonio.instruments.rate_acquire import acquire_rate

        prog = hook(str(protocol), dict(metadata or {}))
        return acquire_rate(prog.segments, prog.metadata, resources, out, resume=resume,
                            room_temperature_c=prog.room_temperature_c, timeout_s=timeout_s,
                            prompt=prompt)
    from gonio.instruments.acquire import acquire as acquire_optical
    from gonio.protocol import load_protocol

    for role in ("table", "gyro"):
        if not resources.get(role):
            raise GonioError(f"the programme needs the {role}: give its VISA resource")
    return acquire_optical(load_protocol(protocol), resources["table"], resources["gyro"], out,
                           resume=resume, metadata=dict(metadata or {}), timeout_s=timeout_s,
                           prompt=prompt)
