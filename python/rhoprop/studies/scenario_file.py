"""TOML scenario files for ``rhoprop run``: parsed and validated with errors naming the
bad key, then run as an ensemble. See ``examples/scenario.toml`` for the schema."""

from __future__ import annotations

import dataclasses
import hashlib
import json
import math
import sys
from dataclasses import fields
from pathlib import Path
from typing import Any

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

from ..density import DensityModel, Exponential, Msis
from ..ensemble import ensemble
from ..errors import ScenarioError
from ..io import OutputFolder, command_line, sanitise, write_oem
from ..propagation import MonteCarlo, OrbitState, Spacecraft, kappa
from ..propagation.methods import from_name
from ..spaceweather import SpaceWeather
from ..time import to_datetime64
from .plots import ensemble_figure

SECTIONS = {"scenario", "state", "spacecraft", "models", "method", "output"}
#: kappa.type -> (process class, its parameter names): the kinds the core knows.
KAPPA_TYPES = {
    kind: (cls, {f.name for f in fields(cls)})  # type: ignore[arg-type]
    for kind, cls in kappa.KINDS.items()
}

__all__ = ["ScenarioError", "load_scenario", "run_scenario_file"]


def _table(doc: dict[str, Any], key: str) -> dict[str, Any]:
    value = doc.get(key)
    if not isinstance(value, dict):
        raise ScenarioError(f"[{key}] is missing or not a table")
    return value


def _get(table: dict[str, Any], where: str, key: str, kind: Any, default: Any = ...) -> Any:
    if key not in table:
        if default is ...:
            raise ScenarioError(f"{where}.{key} is missing")
        return default
    value = table[key]
    if kind is float and isinstance(value, int) and not isinstance(value, bool):
        value = float(value)
    if not isinstance(value, kind) or (isinstance(value, bool) and kind is not bool):
        name = getattr(kind, "__name__", str(kind))
        raise ScenarioError(f"{where}.{key} must be a {name}, got {value!r}")
    return value


def _unknown(table: dict[str, Any], where: str, allowed: set[str]) -> None:
    extra = set(table) - allowed
    if extra:
        raise ScenarioError(
            f"{where} has unknown key(s) {sorted(extra)}; allowed: {sorted(allowed)}"
        )


def _space_weather(value: str, where: str, cache: dict[str, SpaceWeather]) -> SpaceWeather:
    if value not in cache:
        if value == "observed":
            cache[value] = SpaceWeather()
        elif value == "mean-geomagnetic":
            cache[value] = SpaceWeather().mean_geomagnetic()
        elif value == "forecast":
            # The newest record at hand, its predicted rows as drivers: runs past the
            # last observed day (with growing uncertainty and a warning).
            cache[value] = SpaceWeather.cached().with_forecast()
        elif Path(value).exists():
            cache[value] = SpaceWeather(value)
        else:
            raise ScenarioError(
                f"{where}.space_weather must be 'observed', 'mean-geomagnetic', 'forecast' or "
                f"an existing file, got {value!r}"
            )
    return cache[value]


def _model(
    entry: Any, where: str, cache: dict[str, SpaceWeather]
) -> tuple[str, DensityModel, bool, float]:
    if not isinstance(entry, dict):
        raise ScenarioError(f"{where} must be a table")
    name = _get(entry, where, "name", str)
    kind = _get(entry, where, "type", str)
    reference = _get(entry, where, "reference", bool, False)
    weight = _get(entry, where, "weight", float, 1.0)
    if not (math.isfinite(weight) and weight >= 0):
        raise ScenarioError(f"{where} ({name!r}).weight must be a number >= 0, got {weight}")
    common = {"name", "type", "reference", "weight"}
    try:
        if kind == "msis":
            _unknown(entry, where, common | {"version", "space_weather"})
            sw = _space_weather(_get(entry, where, "space_weather", str, "observed"), where, cache)
            model: DensityModel = Msis(_get(entry, where, "version", str, "2.1"), space_weather=sw)
        elif kind == "exponential":
            _unknown(entry, where, common | {"rho0", "h0", "scale_height", "rel_sigma"})
            model = Exponential(
                _get(entry, where, "rho0", float),
                _get(entry, where, "h0", float),
                _get(entry, where, "scale_height", float),
                _get(entry, where, "rel_sigma", float, 0.0),
            )
        else:
            raise ScenarioError(f"{where}.type must be 'msis' or 'exponential', got {kind!r}")
    except ScenarioError:
        raise
    except (ValueError, TypeError) as err:
        raise ScenarioError(f"{where}: {err}") from err
    return name, model, reference, weight


def load_scenario(path: str | Path) -> dict[str, Any]:
    """Parses and validates a scenario file into the arguments of
    :func:`rhoprop.ensemble` plus ``name`` and ``directory``."""
    p = Path(path)
    try:
        doc = tomllib.loads(p.read_text())
    except FileNotFoundError as err:
        raise ScenarioError(f"scenario file {p} does not exist") from err
    except tomllib.TOMLDecodeError as err:
        raise ScenarioError(f"{p} is not valid TOML: {err}") from err
    _unknown(doc, "the file", SECTIONS)
    sc = _table(doc, "scenario")
    _unknown(sc, "scenario", {"name", "epoch", "duration"})
    st = _table(doc, "state")
    _unknown(st, "state", {"position", "velocity", "frame"})
    cr = _table(doc, "spacecraft")
    _unknown(cr, "spacecraft", {"cd", "area_to_mass", "cr"})
    try:
        epoch = to_datetime64(_get(sc, "scenario", "epoch", str), "epoch")
    except (ValueError, TypeError) as err:
        raise ScenarioError(f"scenario.epoch: {err}") from err
    try:
        state = OrbitState(
            epoch,
            _get(st, "state", "position", list),
            _get(st, "state", "velocity", list),
            _get(st, "state", "frame", str) if "frame" in st else "GCRF",
        )
    except (ValueError, TypeError) as err:
        raise ScenarioError(f"[state]: {err}") from err
    try:
        craft = Spacecraft(
            _get(cr, "spacecraft", "cd", float),
            _get(cr, "spacecraft", "area_to_mass", float),
            _get(cr, "spacecraft", "cr", float, None),
        )
    except ValueError as err:
        raise ScenarioError(f"[spacecraft]: {err}") from err
    duration = _get(sc, "scenario", "duration", float)
    if not duration > 0:
        raise ScenarioError(f"scenario.duration must be > 0, got {duration}")

    entries = doc.get("models")
    if not isinstance(entries, list) or not entries:
        raise ScenarioError("[[models]] must list at least one model")
    cache: dict[str, SpaceWeather] = {}
    models, weights, references = {}, [], []
    for i, entry in enumerate(entries):
        name, model, is_ref, weight = _model(entry, f"models[{i}]", cache)
        if name in models:
            raise ScenarioError(f"models[{i}].name {name!r} is used twice")
        models[name] = model
        weights.append(weight)
        if is_ref:
            references.append(name)
    if len(references) != 1:
        raise ScenarioError(f"exactly one model must have reference = true, got {references}")

    me = _table(doc, "method")
    kind = _get(me, "method", "kind", str, MonteCarlo.name)
    if kind not in METHOD_KEYS:
        raise ScenarioError(f"method.kind must be 'monte_carlo' or 'ccsp', got {kind!r}")
    try:
        method = from_name(kind, **_method_options(me, kind))
    except (ValueError, TypeError) as err:
        raise ScenarioError(f"[method]: {err}") from err
    outp = doc.get("output", {})
    if not isinstance(outp, dict):
        raise ScenarioError("[output] must be a table")
    _unknown(outp, "output", {"directory"})
    return {
        "name": _get(sc, "scenario", "name", str, p.stem),
        "directory": _output_directory(p, _get(outp, "output", "directory", str, "rhoprop-run")),
        "state": state,
        "spacecraft": craft,
        "models": models,
        "reference": references[0],
        "method": method,
        "weights": weights,
        "duration": duration,
    }


#: Settings of each method; the other method's settings may stay in the file (so switching
#: ``kind`` is a one-word change) and are then ignored.
METHOD_KEYS = {
    "monte_carlo": {"members", "seed", "output_step", "kappa", "perturbation", "drag_sigma"},
    "ccsp": {"update_interval", "perturbation", "drag_sigma"},
}


#: The type of each method setting in a file, and the method's name of those spelt
#: otherwise (a file's ``members`` is ``n``).
SETTING_TYPES: dict[str, type] = {
    "members": int,
    "seed": int,
    "output_step": float,
    "update_interval": float,
    "perturbation": str,
    "drag_sigma": float,
}
SETTING_NAMES = {"members": "n"}


def _method_options(me: dict[str, Any], kind: str) -> dict[str, Any]:
    """Settings of ``kind`` (None: the method's default) from ``[method]``: its own keys
    at the top of the table or in a ``[method.monte_carlo]`` / ``[method.ccsp]``
    sub-table; the other method's keys and sub-table are ignored (its sub-table's keys
    are still checked)."""
    _unknown(me, "method", {"kind", *METHOD_KEYS, *set().union(*METHOD_KEYS.values())})
    table = {k: v for k, v in me.items() if k in METHOD_KEYS[kind]}
    where = "method"
    if kind in me:
        sub = _get(me, "method", kind, dict)
        _unknown(sub, f"method.{kind}", METHOD_KEYS[kind])
        table.update(sub)
        where = f"method.{kind}"
    for other, keys in METHOD_KEYS.items():
        # Unused, but checked: a typo there should not wait for the switch.
        if other != kind and other in me:
            _unknown(_get(me, "method", other, dict), f"method.{other}", keys)
    options: dict[str, Any] = {
        SETTING_NAMES.get(key, key): _get(table, where, key, SETTING_TYPES[key], None)
        for key in METHOD_KEYS[kind] - {"kappa"}
    }
    if "kappa" in table:
        kp = _get(table, where, "kappa", dict)
        ktype = _get(kp, f"{where}.kappa", "type", str)
        if ktype not in KAPPA_TYPES:
            raise ScenarioError(
                f"{where}.kappa.type must be one of {sorted(KAPPA_TYPES)}, got {ktype!r}"
            )
        cls, params = KAPPA_TYPES[ktype]
        _unknown(kp, f"{where}.kappa", params | {"type"})
        try:
            options["kappa"] = cls(**{k: float(kp[k]) for k in params if k in kp})
        except (ValueError, TypeError) as err:
            raise ScenarioError(f"{where}.kappa: {err}") from err
    return options


def _output_directory(scenario: Path, value: str) -> Path:
    """``output.directory``: an absolute path as given; a relative one resolves against
    the scenario file's folder and must stay inside it (a file from elsewhere must not
    write to ``../../..``)."""
    if not value.strip():
        raise ScenarioError("output.directory must not be empty")
    given = Path(value).expanduser()
    if given.is_absolute():
        return given
    base = scenario.resolve().parent
    target = (base / given).resolve()
    if target != base and base not in target.parents:
        raise ScenarioError(
            f"output.directory {value!r} leads outside the scenario's folder {base}; give "
            "a path inside it, an absolute path, or --out"
        )
    if target == base:
        raise ScenarioError(
            f"output.directory {value!r} is the scenario's own folder; name a subfolder"
        )
    return target


def oem_ids(names: list[str]) -> dict[str, str]:
    """Object ids (and so OEM file names) of the scenario's models: the name as safe
    ASCII, spaces and slashes as ``_``; names that would share an id ("X/Y" and "X_Y",
    "é" and "ü", long names that differ past the cut) all get 8 hex digits of their
    name's SHA-256 appended, so that no model's file replaces another's."""
    plain = {n: sanitise(n, 80).replace(" ", "_").replace("/", "_") or "MODEL" for n in names}
    counts: dict[str, int] = {}
    for oid in plain.values():
        counts[oid] = counts.get(oid, 0) + 1
    return {
        n: oid if counts[oid] == 1 else f"{oid}_{hashlib.sha256(n.encode()).hexdigest()[:8]}"
        for n, oid in plain.items()
    }


def run_scenario_file(
    path: str | Path,
    out: str | Path | None = None,
    *,
    overwrite: bool = False,
    command: str | None = None,
    seed: int | None = None,
) -> int:
    """Runs a scenario file: the ensemble, its figure, summary.json, summary.md and
    manifest.json, in ``out`` (relative to the working directory) or else the file's
    ``output.directory`` (relative to the scenario file's folder). A folder holding an
    earlier run's files is refused unless ``overwrite`` (which clears it). ``seed``
    overrides the file's Monte Carlo seed."""
    sc = load_scenario(path)
    if seed is not None and isinstance(sc["method"], MonteCarlo):
        sc["method"] = dataclasses.replace(sc["method"], seed=int(seed))
    folder = OutputFolder(
        Path(out) if out is not None else sc["directory"],
        command=command or command_line(),
        overwrite=overwrite,
    )
    directory = folder.directory
    name = sanitise(sc["name"])
    print(
        f"rhoprop run: {name}: {len(sc['models'])} models, {sc['method'].name}, "
        f"{sc['duration'] / 86400:g} days"
    )
    ens = ensemble(
        sc["state"],
        sc["spacecraft"],
        sc["models"],
        sc["reference"],
        method=sc["method"],
        weights=sc["weights"],
        duration=sc["duration"],
    )
    with folder.path("ensemble.png") as tmp:
        ensemble_figure({name: ens}, tmp)
    written = [directory / "ensemble.png"]
    ids = oem_ids(list(ens.results))
    folder.expect([directory / "oem" / f"{oid}.oem" for oid in ids.values()])
    for model_name, result in ens.results.items():
        oid = ids[model_name]
        paths = write_oem(
            result, directory / "oem", object_name=name, object_id=oid, originator="rhoprop run"
        )
        folder.add(paths)
        written += paths
    try:
        dataset = ens.to_xarray()
    except ImportError as err:
        print(f"  (no ensemble.nc: {err})")
    else:
        with folder.path("ensemble.nc") as tmp:
            dataset.to_netcdf(tmp, engine="h5netcdf")
        written.append(directory / "ensemble.nc")
    summary = {"scenario": sc["name"], "epoch": str(sc["state"].epoch) + "Z", **ens.summary()}
    folder.write_text("summary.json", json.dumps(summary, indent=2))
    lines = [
        "| model | Cd | along-track mean [m] | along-track std [m] |",
        "| --- | --- | --- | --- |",
    ]
    for model, m in summary["models"].items():
        lines.append(
            f"| {sanitise(model).replace('|', '/')} | {m['cd']:.4f} "
            f"| {m['along_track_mean_m']:.1f} | {m['along_track_std_m']:.1f} |"
        )
    mix = summary["mixture"]
    lines.append(f"| mixture ({mix['modes']} modes) | | {mix['mean_m']:.1f} | {mix['std_m']:.1f} |")
    table = "\n".join(lines)
    folder.write_text("summary.md", f"# {name}\n\n{table}\n")
    manifest = folder.finish()
    print(table)
    for path in [*written, directory / "summary.json", directory / "summary.md", manifest]:
        print(f"  wrote {path}")
    return 0
