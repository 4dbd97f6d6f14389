"""Element sets: TLE and CCSDS OMM input through ``sgp4``.

Frames: the SGP4 state at an element set's epoch is in TEME, which rhoprop takes as its
inertial frame (the difference to J2000 is a slow precession-nutation rotation that the
design contract neglects). Drag: Cd*A/m = 2 B* / rho0 with B* in 1/Earth radii and
rho0 = 0.15696615 kg m^-2 ER^-1 (the SGP4 reference density 2.461e-8 kg/m^3 times one Earth
radius), i.e. 12.7416 B* m^2/kg, unless the caller gives a drag parameter per object.
"""

from __future__ import annotations

import csv
import dataclasses
import io
import json
import math
import re
import warnings
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, Literal, NoReturn, TypedDict

import numpy as np

from .. import _validate
from ..density.model import ModelLike
from ..options import Errors
from ..parallel import worker_count
from ..propagation import OrbitState
from ..propagation.dynamics import Dynamics
from ..propagation.propagate import check_model
from ..propagation.state import MAX_RADII, radii_beyond_reach
from ..time import from_jd
from .fit import (
    DEFAULT_DRAG_PARAMETER,
    SGP4_RHO0,
    LooseDegree,
    drag_parameter_from_bstar,
    fit_dynamics,
)

if TYPE_CHECKING:
    from typing_extensions import Unpack

__all__ = [
    "DEFAULT_DRAG_PARAMETER",
    "SGP4_RHO0",
    "Catalog",
    "CatalogObject",
    "drag_parameter_from_bstar",
    "load",
]


@dataclass(frozen=True)
class CatalogObject:
    """One element set: ``state`` at its epoch (TEME taken as inertial), the drag
    parameter Cd*A/m (m^2/kg), B* (1/ER) and where it came from.

    Attributes:
        covariance: the object's own initial covariance (6, 6) at its epoch (m^2, m^2/s,
            m^2/s^2, inertial), or None: ``load`` sets the published TLE accuracy
            (:func:`~rhoprop.catalog.covariance.tle_covariance`), ``load(fit=True)`` that
            plus the fit's own covariance.
        covariance_note: what ``covariance`` includes, in words (OEM comment, summary).
        fit: the :class:`~rhoprop.catalog.fit.FitResult` when the state and drag
            parameter were fitted (``load(fit=True)``), else None.
        elements: the element set as read (TLE lines or the OMM record), to rebuild the
            SGP4 propagator (``Satrec`` does not pickle).
        element_sets: how many element sets of the input the object stands for: with
            ``load(history="newest")`` (the default) the newest of them; 1 otherwise.
    """

    name: str
    norad_id: int
    state: OrbitState
    drag_parameter: float
    bstar: float
    source: str
    covariance: np.ndarray | None = field(default=None, repr=False, compare=False)
    covariance_note: str = field(default="", compare=False)
    fit: Any = field(default=None, repr=False, compare=False)
    elements: Any = field(default=None, repr=False, compare=False)
    element_sets: int = field(default=1, compare=False)

    def satrec(self) -> Any:
        """A fresh ``sgp4`` ``Satrec`` of the element set (None without ``elements``)."""
        from sgp4 import omm
        from sgp4.api import Satrec

        if self.elements is None:
            return None
        if isinstance(self.elements, dict):
            sat = Satrec()
            omm.initialize(sat, self.elements)
            return sat
        return Satrec.twoline2rv(*self.elements)


@dataclass
class Catalog:
    """Objects read from a file, and the entries skipped as (where, message) pairs: with
    ``errors="record"`` the unusable ones, and (``far_orbits="skip"``, the default)
    those beyond :data:`~rhoprop.propagation.state.MAX_RADII` Earth radii at their
    epoch."""

    objects: list[CatalogObject]
    skipped: list[tuple[str, str]] = field(default_factory=list)

    def __len__(self) -> int:
        return len(self.objects)

    def __iter__(self) -> Iterator[CatalogObject]:
        return iter(self.objects)

    def __getitem__(self, i: int) -> CatalogObject:
        return self.objects[i]


class _FarOrbit(ValueError):
    """A valid element set whose epoch position lies beyond the radius rhoprop takes."""

    def __init__(self, message: str, norad: int, epoch: np.datetime64) -> None:
        super().__init__(message)
        self.norad, self.epoch = norad, epoch


def _object_from_satrec(
    sat: Any,
    name: str,
    where: str,
    drag: float | None,
    elements: Any = None,
    allow_nonpositive: bool = False,
) -> CatalogObject:
    from sgp4.api import SGP4_ERRORS

    from .covariance import tle_accuracy, tle_covariance

    err, r, v = sat.sgp4(sat.jdsatepoch, sat.jdsatepochF)
    if err:
        raise ValueError(f"{where}: SGP4 error {err} at the epoch: {SGP4_ERRORS.get(err, '')}")
    if not np.isfinite([*r, *v]).all():
        # SGP4 reports no error for some impossible elements (a mean motion of 1e300
        # rev/day: semi-major axis 1e-200 Earth radii) and returns NaN.
        raise ValueError(
            f"{where}: SGP4 gives no finite state at the epoch (mean motion "
            f"{sat.no_kozai * 1440 / (2 * np.pi):.6g} rev/day, eccentricity {sat.ecco:.6g}): "
            "the elements describe no orbit"
        )
    # A TLE epoch counts 86400-s days on the UTC calendar (no leap seconds).
    epoch = from_jd(sat.jdsatepoch, sat.jdsatepochF, scale="utc")
    bstar = float(sat.bstar)
    if drag is None:
        if bstar > 0:
            drag = drag_parameter_from_bstar(bstar)
        elif allow_nonpositive:  # the fit replaces it; a typical value to start from
            drag = DEFAULT_DRAG_PARAMETER
        else:
            raise ValueError(
                f"{where}: B* = {bstar} is not positive, so no drag parameter follows from it; "
                "load with fit=True (fits Cd*A/m to the element set) or give drag_parameters "
                "for this object"
            )
    radii = radii_beyond_reach(np.array(r) * 1e3)
    if radii is not None:  # a real orbit (TESS, IBEX, lunar transfers), not bad input
        raise _FarOrbit(
            f"{name.strip() or sat.satnum} (NORAD {sat.satnum}) is {radii:.3g} Earth radii "
            f"from the centre at its epoch, beyond the {MAX_RADII:g} rhoprop propagates",
            int(sat.satnum),
            epoch,
        )
    state = OrbitState(epoch, np.array(r) * 1e3, np.array(v) * 1e3, "TEME")
    acc = tle_accuracy(state)
    note = _tle_note(acc)
    if bstar <= 0 and drag == DEFAULT_DRAG_PARAMETER:
        note += f"; B* = {bstar:g} <= 0: Cd*A/m = {drag:g} m^2/kg assumed (unless fitted)"
    return CatalogObject(
        name or str(sat.satnum),
        int(sat.satnum),
        state,
        drag,
        bstar,
        where,
        covariance=tle_covariance(state, acc),
        covariance_note=note,
        elements=elements,
    )


def _tle_note(acc: Any) -> str:
    return (
        f"initial covariance: published TLE accuracy ({acc.regime}: RMS radial "
        f"{acc.radial:.0f} m, along-track {acc.along_track:.0f} m, cross-track "
        f"{acc.cross_track:.0f} m, drift {acc.drift_rate * 86400 / 1e3:.1f} km/day)"
    )


def _checksum_ok(line: str) -> bool:
    total = sum(int(c) if c.isdigit() else (1 if c == "-" else 0) for c in line[:68])
    return line[68].isdigit() and total % 10 == int(line[68])


_NUMBER = r" *(\d+\.?\d*|\.\d+)"
_SIGNED_DECIMAL = r" *[+-]?\d*\.\d+"
_EXPONENT = r" *[+-]?\d{1,5}[ +-]\d"  # an implied-decimal mantissa and exponent: -11606-4
_DIGITS = r" *\d*"
#: The numeric fields of a TLE's two lines: (line, first and last column (1-based), name,
#: form, allowed range). sgp4 reads a field up to its first bad character (mean motion
#: "15.523O4312" read as 15.523) and folds angles out of range, so each is checked whole.
_TLE_FIELDS = (
    (1, 19, 20, "epoch year", r"[ \d]\d", None),
    (1, 21, 32, "epoch day", r" *\d{1,3}\.\d*", (1.0, 367.0)),
    (1, 34, 43, "first derivative of mean motion", _SIGNED_DECIMAL, None),
    (1, 45, 52, "second derivative of mean motion", _EXPONENT, None),
    (1, 54, 61, "B*", _EXPONENT, None),
    (1, 63, 63, "ephemeris type", r"[ \d]", None),
    (1, 65, 68, "element set number", _DIGITS, None),
    (2, 9, 16, "inclination", _NUMBER, (0.0, 180.0)),
    (2, 18, 25, "right ascension of the ascending node", _NUMBER, (0.0, 360.0)),
    (2, 27, 33, "eccentricity", r" *\d{1,7}", None),
    (2, 35, 42, "argument of perigee", _NUMBER, (0.0, 360.0)),
    (2, 44, 51, "mean anomaly", _NUMBER, (0.0, 360.0)),
    (2, 53, 63, "mean motion", _NUMBER, None),
    (2, 64, 68, "revolution number", _DIGITS, None),
)


def _tle_field_problem(lines: tuple[tuple[int, str], tuple[int, str]]) -> str | None:
    """What is wrong with a TLE's numeric fields (naming the line, columns and field), or
    None."""
    for line, first, last, name, form, bounds in _TLE_FIELDS:
        number, text = lines[line - 1]
        field = text[first - 1 : last]
        where = f"line {number} columns {first}-{last} ({name}) = {field!r}"
        if not re.fullmatch(form, field):
            return f"{where} is not a number of the TLE's form"
        if bounds is not None and not bounds[0] <= float(field) <= bounds[1]:
            return f"{where} is outside {bounds[0]:g}-{bounds[1]:g}"
        if name == "mean motion" and float(field) <= 0.0:
            return f"{where} is not positive"
    return None


def _parse_tle(text: str, path: str) -> list[tuple[str, Any]]:
    """(where, callable returning an object) per TLE in ``text``."""
    from sgp4.api import Satrec

    lines = [(i + 1, ln.rstrip()) for i, ln in enumerate(text.splitlines()) if ln.strip()]
    entries: list[tuple[str, Any]] = []
    k = 0
    while k < len(lines):
        name = ""
        _n0, first = lines[k]
        if not first.startswith("1 ") and k + 1 < len(lines) and lines[k + 1][1].startswith("1 "):
            name = first[2:].strip() if first.startswith("0 ") else first.strip()
            k += 1
        if k + 1 >= len(lines):
            entries.append((f"{path} line {lines[k][0]}", ValueError("a TLE needs two lines")))
            break
        (n1, l1), (n2, l2) = lines[k], lines[k + 1]
        k += 2
        where = f"{path} lines {n1}-{n2}"
        problem = None
        for n, ln, tag in ((n1, l1, "1"), (n2, l2, "2")):
            if not ln.startswith(tag + " "):
                problem = f"line {n} should start with '{tag} '"
            elif len(ln) < 69:
                problem = f"line {n} has {len(ln)} characters, a TLE line has 69"
            elif not _checksum_ok(ln):
                problem = f"line {n} fails its checksum (column 69)"
            if problem:
                break
        if problem is None and l1[2:7] != l2[2:7]:
            problem = f"catalog numbers differ: {l1[2:7]!r} on line {n1}, {l2[2:7]!r} on line {n2}"
        if problem is None:
            problem = _tle_field_problem(((n1, l1), (n2, l2)))
        if problem:
            entries.append((where, ValueError(f"{where}: {problem}")))
            continue
        try:
            sat = Satrec.twoline2rv(l1, l2)
        except (ValueError, IndexError) as err:
            entries.append((where, ValueError(f"{where}: unreadable field: {err}")))
            continue
        entries.append((where, (sat, name, (l1, l2))))
    return entries


#: OMM fields sgp4 reads as numbers, by the type it converts them to.
_OMM_FLOATS = (
    "ARG_OF_PERICENTER",
    "BSTAR",
    "ECCENTRICITY",
    "INCLINATION",
    "MEAN_ANOMALY",
    "MEAN_MOTION_DDOT",
    "MEAN_MOTION_DOT",
    "MEAN_MOTION",
    "RA_OF_ASC_NODE",
)
_OMM_INTS = ("EPHEMERIS_TYPE", "ELEMENT_SET_NO", "REV_AT_EPOCH", "NORAD_CAT_ID")
#: Ranges of the integer fields (inclusive): what a catalog number, an element-set
#: counter and a revolution count can be, and within sgp4's 32-bit integers (a larger
#: value overflowed inside sgp4 and stopped the whole load).
_OMM_INT_RANGES = {
    "EPHEMERIS_TYPE": (0, 9),
    "ELEMENT_SET_NO": (0, 99_999),
    "REV_AT_EPOCH": (0, 99_999_999),
    "NORAD_CAT_ID": (1, 999_999_999),
}


def _checked_omm(rec: dict[str, Any]) -> dict[str, Any]:
    """The OMM record with each field sgp4 reads checked (ValueError naming the field
    and its value) and EPOCH in the form sgp4 parses (fractional seconds added, a
    trailing Z dropped: both are valid CCSDS epochs)."""
    out = dict(rec)
    for name in (*_OMM_FLOATS, *_OMM_INTS):
        if name not in rec:
            continue  # sgp4's KeyError names it
        value = rec[name]
        try:
            if isinstance(value, bool):
                raise ValueError
            number = float(value) if name in _OMM_FLOATS else int(str(value).strip())
        except (TypeError, ValueError):
            raise ValueError(f"unreadable field {name} = {value!r}") from None
        if not math.isfinite(number):
            raise ValueError(f"unreadable field {name} = {value!r}")
        if name in _OMM_INT_RANGES:
            low, high = _OMM_INT_RANGES[name]
            if not low <= number <= high:
                raise ValueError(f"field {name} = {value!r} is outside {low}-{high:,}")
    if "EPOCH" in rec:
        epoch = rec["EPOCH"]
        if not isinstance(epoch, str):
            raise ValueError(f"unreadable field EPOCH = {epoch!r}")
        text = epoch.strip().removesuffix("Z")
        if not re.fullmatch(r"\d{4}-\d{2}-\d{2}T\d{2}:\d{2}:\d{2}(\.\d+)?", text):
            raise ValueError(f"unreadable field EPOCH = {epoch!r} (CCSDS: YYYY-MM-DDThh:mm:ss)")
        out["EPOCH"] = text if "." in text else text + ".0"
    return out


def _parse_omm(text: str, path: str) -> list[tuple[str, Any]]:
    from xml.etree.ElementTree import ParseError

    from sgp4 import omm
    from sgp4.api import Satrec

    stripped = text.lstrip()
    if stripped.startswith(("[", "{")):
        try:
            data = _validate.json_text(text, str(path))
        except json.JSONDecodeError as err:
            raise ValueError(f"{path}: not valid OMM JSON ({err})") from None
        records = data if isinstance(data, list) else [data]
        kind = "JSON"
    elif stripped.startswith("<"):
        try:
            records = list(omm.parse_xml(io.StringIO(text)))
        except ParseError as err:
            raise ValueError(f"{path}: not valid OMM XML ({err})") from None
        kind = "XML"
    else:
        records = list(csv.DictReader(io.StringIO(text)))
        kind = "CSV"
    entries: list[tuple[str, Any]] = []
    for i, rec in enumerate(records):
        where = f"{path} {kind} record {i}"
        if not isinstance(rec, dict):
            entries.append((where, ValueError(f"{where}: not a record")))
            continue
        sat = Satrec()
        try:
            checked = _checked_omm(rec)
            omm.initialize(sat, checked)
        except KeyError as err:
            entries.append((where, ValueError(f"{where}: missing field {err}")))
            continue
        except (ValueError, TypeError) as err:
            text = (
                str(err) if str(err).startswith("unreadable field") else f"unreadable field: {err}"
            )
            entries.append((where, ValueError(f"{where}: {text}")))
            continue
        # The checked record: ``CatalogObject.satrec`` parses it again.
        entries.append((where, (sat, str(rec.get("OBJECT_NAME", "")).strip(), checked)))
    return entries


#: Element sets of one object older than this before its newest (days) are not fitted
#: with it: over longer arcs one constant Cd*A/m carries the model's density errors of
#: past days into the prediction. On the dense 2026 history (a set every ~6 h) one day
#: beat two and three; on the 2023 snapshots (sets 3-85 days apart) no older set helped
#: (docs/catalog-realism.md, "What changed: B* as the prior, weights, history fits").
HISTORY_DAYS = 1.0


#: The dynamics of a fit at load: J2..J4, the degree of catalog runs.
FIT_DYNAMICS = Dynamics(zonal_degree=4)


@dataclass(frozen=True)
class FitSettings:
    """How :func:`load` fits each object's state and Cd*A/m to its element set
    (``load(path, fit=FitSettings(model))``), checked when made.

    Attributes:
        model: the density model of the fit: a sampled model is sampled once into one
            field covering every object's span and altitudes; a ``DensityField`` is used
            as given.
        span: fit span, s from each epoch (None: :func:`~rhoprop.catalog.fit.default_span`,
            the day before the epoch; for deep-space orbits three days either side of it
            when near-circular, one when eccentric).
        dynamics: the fit's :class:`~rhoprop.Dynamics` (None: ``Dynamics(zonal_degree=4)``,
            J2..J4, the degree of catalog runs; fit with the degree the objects will be
            propagated with). The fit integrates on its own RK8 grid down to the default
            floor: an ``integrator``, ``step``, ``rtol``, another ``floor_altitude``,
            ``field_degree`` or ``third_bodies`` is refused (ValueError).
        threads: objects fitted at once (None: every core).
        along_track_bias: SGP4's systematic along-track error by TLE-accuracy regime, m
            (its position minus the truth), removed from the positions each fit is made
            to (TLE debiasing; None: :data:`rhoprop.catalog.fit.ALONG_TRACK_BIAS`, measured
            on precise orbits: MEO -490 m, GEO -370 m, none in LEO; ``{}``: none); applied
            to deep-space element sets (SDP4's, periods of 225 min or more).

    Example:
        >>> import rhoprop as rp
        >>> rp.catalog.FitSettings(rp.density.Exponential.benchmark()).span is None
        True
    """

    model: ModelLike
    span: tuple[float, float] | None = None
    dynamics: Dynamics | None = None
    threads: int | None = None
    # checked into a dict: left out of the hash, which the other fields still give
    along_track_bias: Mapping[str, float] | None = field(default=None, hash=False)

    def __post_init__(self) -> None:
        from .fit import along_track_biases

        check_model(self.model)
        object.__setattr__(self, "along_track_bias", along_track_biases(self.along_track_bias))
        dyn = fit_dynamics("FitSettings", self.dynamics, default=FIT_DYNAMICS)
        object.__setattr__(self, "dynamics", dyn)
        if self.threads is not None:
            object.__setattr__(
                self, "threads", worker_count(_validate.count("threads", self.threads, minimum=1))
            )


class LoadKeywords(TypedDict, total=False):
    """The deprecated keywords of :func:`load`, now in ``fit=FitSettings(model, span=,
    dynamics=, threads=)`` (``zonal_degree`` in its ``dynamics``)."""

    model: ModelLike | None
    span: tuple[float, float] | None
    threads: int | None
    zonal_degree: int


def load(
    path: str | Path | Sequence[str | Path],
    *,
    errors: Errors | Literal["skip"] = "raise",
    drag_parameters: dict[int, float] | None = None,
    fit: bool | FitSettings = False,
    nonpositive_bstar: Literal["error", "prior"] = "prior",
    history: Literal["newest", "fit", "each"] = "newest",
    far_orbits: Literal["skip", "error"] = "skip",
    **deprecated: Unpack[LoadKeywords],
) -> Catalog:
    """Reads a TLE file (2- or 3-line) or a CCSDS OMM file (JSON, CSV or XML as CelesTrak
    serves them), detected by content, plain or gzip-compressed.

    Every object gets an initial ``covariance``: the published accuracy of TLE-derived
    states for its regime (:mod:`rhoprop.catalog.covariance`), and a ``covariance_note``
    saying so.

    Args:
        path: the file, or several (e.g. snapshots of a catalog at different dates),
            read in turn.
        errors: ``"raise"`` (default): the first malformed line/record (or failed fit of
            a B* <= 0 object) raises ValueError naming it and the field; ``"record"``:
            it is skipped and listed in ``Catalog.skipped`` (``"skip"``, its old name,
            still works with a DeprecationWarning).
        drag_parameters: optional {NORAD id: Cd*A/m (m^2/kg)} overriding B* (with
            ``fit=True``: the fit's starting value and prior).
        fit: a :class:`FitSettings` (its model, span, dynamics and threads): fit each
            object's state and Cd*A/m to its SGP4 positions over the span with rhoprop's
            dynamics and the model (:func:`~rhoprop.catalog.fit.fit_element_set`, about
            0.1 s per object). Fitted objects carry ``fit`` (residuals, covariance) and as
            ``covariance`` the TLE accuracy plus the fit's state covariance. Objects with
            B* <= 0 load only this way. Where a fit fails (the orbit decays within the
            span, SGP4 fails) the object keeps its B* state, and its note says why.
            False (default): the B* conversion, instant (a fit needs a density model and
            space weather over the span). ``fit=True`` with ``model=`` (deprecated) is
            ``FitSettings(model)``.
        nonpositive_bstar: an element set with B* <= 0 (no drag parameter follows from it)
            without ``fit``: ``"prior"`` (default): it loads with the fit's starting value
            Cd*A/m = ``fit.DEFAULT_DRAG_PARAMETER`` (0.022 m^2/kg), its note says so,
            ``drag_sigma="auto"`` gives it 100 % (the drag is a guess) and
            ``propagate_catalog`` fits it where it fits low objects: a published catalog
            loads whole (1,656 of the 8,838 element sets of CelesTrak's 2023-11-13
            snapshot have B* <= 0, mostly high orbits where drag does not matter).
            ``"error"``: an error (or skipped with ``errors="record"``), as before 0.2.
        history: several element sets of one NORAD id (a history: snapshots, or a file
            as Space-Track serves them): ``"newest"`` (default) makes them one object, the
            newest element set (fitted alone with ``fit``), whose note counts the others;
            ``"fit"`` (with ``fit=True``) fits its state and Cd*A/m to all of them within
            :data:`HISTORY_DAYS` of the newest, each near its own epoch
            (:func:`~rhoprop.catalog.fit.fit_element_sets`; ``fit.element_sets`` names
            those used); ``"each"``: every element set is its own object. ``"fit"`` is
            not the default because on the development data it does not predict better
            than the newest element set's fit: on every third day of the dense 2026
            history a smaller median error at 1 day, the same at 3, larger at 7
            (docs/catalog-realism.md, "What changed: B* as the prior, weights, history fits").
        far_orbits: an element set whose state at its epoch lies beyond
            :data:`~rhoprop.propagation.state.MAX_RADII` (10) Earth radii, such as TESS's
            (high orbits that published catalogs hold: 4 of the 8,838 element sets of
            CelesTrak's 2023-11-13 snapshot): ``"skip"`` (default, whatever ``errors``):
            it is listed in ``Catalog.skipped`` (and with ``errors="raise"`` a
            RuntimeWarning says how many), so a published catalog loads as it comes;
            ``"error"``: a ValueError (recorded with ``errors="record"``).
        **deprecated: ``model=``, ``span=``, ``threads=`` and ``zonal_degree=`` (with
            ``fit=True``), now in ``fit=FitSettings(...)``, folded in with a
            DeprecationWarning.
    """
    settings = _fit_settings(fit, deprecated)
    if history not in ("newest", "fit", "each"):
        raise ValueError(f"history must be 'newest', 'fit' or 'each', got {history!r}")
    if history == "fit" and settings is None:
        raise ValueError("history='fit' fits element sets together: it needs fit=FitSettings(...)")
    if far_orbits not in ("skip", "error"):
        raise ValueError(f"far_orbits must be 'skip' or 'error', got {far_orbits!r}")
    if nonpositive_bstar not in ("error", "prior"):
        raise ValueError(f"nonpositive_bstar must be 'error' or 'prior', got {nonpositive_bstar!r}")

    errors = _validate.errors_argument("load", errors)
    if drag_parameters is not None:
        if not isinstance(drag_parameters, Mapping):
            raise TypeError(
                "drag_parameters must be a mapping {NORAD id: Cd*A/m (m^2/kg)}, got "
                f"{type(drag_parameters).__name__}"
            )
        for key, value in drag_parameters.items():
            _validate.positive(f"drag_parameters[{key!r}] (Cd*A/m, m^2/kg)", value)
    try:
        paths: list[object] = [path] if isinstance(path, (str, Path)) else list(path)
    except TypeError:
        paths = [path]
    files = [Path(one) for one in paths if isinstance(one, (str, Path))]
    if len(files) != len(paths):
        bad = next(one for one in paths if not isinstance(one, (str, Path)))
        raise TypeError(
            f"path must be a file's path (str or Path) or a sequence of them, got {bad!r:.60}"
        )
    if not paths:
        raise ValueError("load needs at least one file")
    entries = [e for one in files for e in _read_entries(one, errors)]
    out = Catalog([])
    far: dict[int, np.datetime64] = {}  # NORAD id: newest epoch set aside as too far
    for where, item in entries:
        try:
            if isinstance(item, Exception):
                raise item
            sat, name, elements = item
            drag = (drag_parameters or {}).get(int(sat.satnum))
            out.objects.append(
                _object_from_satrec(
                    sat,
                    name,
                    where,
                    drag,
                    elements,
                    allow_nonpositive=settings is not None or nonpositive_bstar == "prior",
                )
            )
        except ValueError as err:
            message = str(err) if str(err).startswith(where) else f"{where}: {err}"
            skip_far = isinstance(err, _FarOrbit) and far_orbits == "skip"
            if errors == "raise" and not skip_far:
                raise ValueError(message) from err
            out.skipped.append((where, str(err)))
            if isinstance(err, _FarOrbit):
                far[err.norad] = max(far.get(err.norad, err.epoch), err.epoch)
    if far and errors == "raise":  # with "record" the list is the report
        _warn_far(len(far))
    if not out.objects and not out.skipped:
        where = str(paths[0]) if len(paths) == 1 else f"{len(paths)} files"
        raise ValueError(f"{where} holds no TLE or OMM element sets")
    older: dict[int, list[CatalogObject]] = {}
    if history != "each":
        out.objects, older = _newest_of_each(out.objects)
        _drop_behind_far(out, older, far)
    if settings is not None and out.objects:
        together = older if history == "fit" else None
        _fit_all(out, settings, errors, together)
    if older and history == "newest":
        out.objects = _noted_histories(out.objects, older)
    return out


def _warn_far(count: int) -> None:
    warnings.warn(
        f"element sets of {count} object{'s' if count > 1 else ''} beyond "
        f"{MAX_RADII:g} Earth radii set aside (Catalog.skipped names them; "
        "far_orbits='error' to stop instead)",
        RuntimeWarning,
        stacklevel=3,
    )


def _drop_behind_far(
    out: Catalog, older: dict[int, list[CatalogObject]], far: dict[int, np.datetime64]
) -> None:
    """Sets aside (into ``out.skipped``) each object whose newest element set was set aside
    as too far (``far``: NORAD id -> its epoch): it is not predicted from an older one
    that happened to lie nearer."""
    stale = [o for o in out.objects if o.norad_id in far and o.state.epoch < far[o.norad_id]]
    for o in stale:
        out.skipped.append(
            (
                o.source,
                f"{o.name} (NORAD {o.norad_id}): its newest element set "
                f"({far[o.norad_id]!s:.19}) is beyond {MAX_RADII:g} Earth radii; "
                "the older ones are set aside with it",
            )
        )
        older.pop(o.norad_id, None)
    gone = {id(o) for o in stale}
    out.objects = [o for o in out.objects if id(o) not in gone]


def _history_note(obj: CatalogObject) -> str:
    """The end of ``obj``'s note when it stands for several element sets (the newest),
    else ""."""
    if obj.element_sets <= 1:
        return ""
    return (
        f"; the newest of {obj.element_sets} element sets (history='fit' or --duplicates "
        "fit fits them together)"
    )


def _noted_histories(
    objects: list[CatalogObject], older: dict[int, list[CatalogObject]]
) -> list[CatalogObject]:
    """``objects`` with the note of those that stand for several element sets."""
    import dataclasses

    out = []
    for o in objects:
        if o.norad_id in older:
            o = dataclasses.replace(o, element_sets=len(older[o.norad_id]) + 1)
            o = dataclasses.replace(o, covariance_note=o.covariance_note + _history_note(o))
        out.append(o)
    return out


#: Largest decompressed size of a gzip catalog file, bytes: the whole public catalog
#: (24,000 objects) is about 5 MB as text, so more is a damaged file or a bomb, and it
#: is refused before it fills the memory.
MAX_INFLATED_BYTES = 1 << 30


def _inflate(p: Path, raw: bytes) -> bytes:
    """The decompressed bytes of the gzip file ``p`` (its content ``raw``), read in
    chunks and refused past :data:`MAX_INFLATED_BYTES`; a damaged file is a ValueError
    naming it."""
    import gzip
    import io
    import zlib

    out = bytearray()
    try:
        with gzip.GzipFile(fileobj=io.BytesIO(raw)) as stream:
            while chunk := stream.read(1 << 20):
                out += chunk
                if len(out) > MAX_INFLATED_BYTES:
                    raise ValueError(
                        f"{p.name}: inflates past {MAX_INFLATED_BYTES:,} bytes, the limit "
                        "of a catalog file (rhoprop.catalog.elements.MAX_INFLATED_BYTES); "
                        "a damaged file or not a catalog"
                    )
    except (OSError, EOFError, zlib.error) as err:
        raise ValueError(f"{p.name}: damaged gzip file ({err})") from err
    return bytes(out)


def _read_entries(p: Path, errors: str) -> list[tuple[str, Any]]:
    """The parsed entries (where, element set or exception) of one file."""
    raw = p.read_bytes()
    if raw[:2] == b"\x1f\x8b":  # gzip, as catalog archives are often stored
        raw = _inflate(p, raw)
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as err:
        if errors == "raise":
            line = raw[: err.start].count(b"\n") + 1
            raise ValueError(
                f"{p.name} line {line}: byte {raw[err.start]:#04x} is not UTF-8 text"
            ) from err
        # Element sets are ASCII: a stray byte becomes U+FFFD, so that a damaged data
        # line fails its own checks (and is skipped) while the rest loads.
        text = raw.decode("utf-8", errors="replace")
    head = text.lstrip()[:200]
    is_omm = head.startswith(("[", "{", "<")) or "NORAD_CAT_ID" in head or "OBJECT_NAME" in head
    return _parse_omm(text, p.name) if is_omm else _parse_tle(text, p.name)


def _newest_of_each(
    objects: list[CatalogObject],
) -> tuple[list[CatalogObject], dict[int, list[CatalogObject]]]:
    """One object per NORAD id, the newest element set (first-seen order kept), and the
    older element sets of each id with several (distinct epochs, ascending)."""
    groups: dict[int, list[CatalogObject]] = {}
    for o in objects:
        groups.setdefault(o.norad_id, []).append(o)
    kept, older = [], {}
    for norad, group in groups.items():
        group.sort(key=lambda o: o.state.epoch)
        newest = _noted_same_epoch(group)
        kept.append(newest)
        rest = [o for o in group[:-1] if o.state.epoch != newest.state.epoch]
        if rest:
            older[norad] = rest
    return kept, older


def _noted_same_epoch(group: list[CatalogObject]) -> CatalogObject:
    """The newest of ``group`` (sorted by epoch; of equal epochs the last in the input),
    its note naming the other element sets of that epoch that differ (they were dropped
    without a word)."""
    newest = group[-1]
    same = [
        o
        for o in group[:-1]
        if o.state.epoch == newest.state.epoch
        and not np.array_equal(o.state.state, newest.state.state)
    ]
    if not same:
        return newest
    gap = max(float(np.linalg.norm(o.state.position - newest.state.position)) for o in same)
    return dataclasses.replace(
        newest,
        covariance_note=f"{newest.covariance_note}; {len(same)} other element set(s) of the "
        f"same epoch set aside (the last in the input kept; positions differ by up to "
        f"{gap / 1e3:.3g} km)",
    )


#: Largest RMS residual (m) of a fit to SGP4 that :func:`fit_objects` accepts: TLE
#: positions agree with a good fit to a few km; tens of km mean the fit diverged.
MAX_FIT_RMS = 20e3
#: A fitted Cd*A/m further than this factor from its prior (a positive B* scaled to the
#: model), or pinned at the fit's floor, is not drag: a manoeuvre or thrust the fit took
#: for it. Such a fit counts as failed and the element set runs unfitted. On the first
#: 3,000 objects of the 2023-11-13 snapshot (NRLMSIS 2.1) 99 % of fits lie within
#: 0.05-1.1x their prior; every one outside 0.1-10x was pinned at the floor (1e-4 m^2/kg),
#: all of them Starlink and OneWeb satellites with B* <= 0, whose prior is only a guess
#: (not judged: B* <= 0 says the element set saw no drag, and the floor agrees).
MAX_PRIOR_FACTOR = 10.0


def fit_objects(
    objects: list[CatalogObject],
    model: ModelLike,
    *,
    span: tuple[float, float] | None = None,
    threads: int | None = None,
    dynamics: Dynamics | None = None,
    history: Mapping[int, Sequence[CatalogObject]] | None = None,
    progress: Callable[[int], object] | None = None,
    along_track_bias: Mapping[str, float] | None = None,
    **deprecated: Unpack[LooseDegree],
) -> list[CatalogObject | Exception]:
    """Each object's state and Cd*A/m fitted to its element set's SGP4 positions
    (:func:`~rhoprop.catalog.fit.fit_element_sets`, ``span`` s around the epoch, default
    :func:`~rhoprop.catalog.fit.default_span`: the day before it; for deep-space orbits
    three days either side when near-circular, one when eccentric; with a span reaching
    past the epoch, an orbit that comes down within it is fitted to the part before the
    epoch instead), in
    the core many objects per call (:func:`~rhoprop.catalog.fit.fit_histories`;
    ``threads`` calls at once), in
    epoch order so that the fits of a call share their day tiles. ``history``: {NORAD
    id: older element sets} fitted together with the object's (those within
    :data:`HISTORY_DAYS` of it). A fit that leaves an RMS residual above
    :data:`MAX_FIT_RMS` (diverged) counts as failed. ``progress(done)`` is told the
    objects finished after each group of fits. ``dynamics``: the fits'
    (:func:`~rhoprop.catalog.fit.fit_dynamics`: a zonal degree, None J2 only;
    ``zonal_degree=`` is deprecated). ``along_track_bias``: as :class:`FitSettings`.
    Returns, in input order, the fitted object (``fit`` set, covariance the TLE accuracy
    plus the fit's) or the exception of a fit that failed."""
    from ..density import SampledModel
    from .fit import DEFAULT_SPAN, default_span, fit_histories

    dyn = fit_dynamics("fit_objects", dynamics, deprecated)
    history = history or {}
    atmosphere = model.atlas if isinstance(model, SampledModel) else model
    histories = []
    for obj in objects:
        oldest = obj.state.epoch - np.timedelta64(int(HISTORY_DAYS * 86400), "s")
        histories.append(
            [*(o for o in history.get(obj.norad_id, ()) if o.state.epoch >= oldest), obj]
        )
    groups: dict[tuple[float, float], list[int]] = {}
    for i, obj in enumerate(objects):
        sat = obj.satrec()
        first = span or (default_span(sat) if sat is not None else DEFAULT_SPAN)
        groups.setdefault((float(first[0]), float(first[1])), []).append(i)
    out: list[Any] = [None] * len(objects)
    finished = 0
    for first, todo in groups.items():
        finished += len(todo)
        tried = [first] if first[1] <= 0.0 else [first, (first[0], 0.0)]
        for window in tried:
            runs = fit_histories(
                [histories[i] for i in todo],
                atmosphere,
                span=window,
                dynamics=dyn,
                threads=threads,
                along_track_bias=along_track_bias,
            )
            for i, f in zip(todo, runs, strict=True):
                out[i] = f if isinstance(f, Exception) else _fitted(objects[i], f, window)
            todo = [i for i in todo if isinstance(out[i], Exception)]
            if not todo:
                break
        if progress is not None:
            progress(finished)
    return out


def _fitted(obj: CatalogObject, f: Any, window: tuple[float, float]) -> CatalogObject | Exception:
    """``obj`` with the state, Cd*A/m and covariance of its fit ``f`` over ``window``, or
    the ValueError of a fit that diverged (RMS residual above :data:`MAX_FIT_RMS`, e.g.
    over an arc running into the decay) or whose Cd*A/m is not drag
    (:data:`MAX_PRIOR_FACTOR`)."""
    import dataclasses

    from .covariance import fitted_accuracy, tle_accuracy, tle_covariance
    from .fit import MIN_DRAG_PARAMETER

    if not f.rms_total <= MAX_FIT_RMS:
        return ValueError(
            f"the fit over {window[0] / 3600:+.0f}..{window[1] / 3600:+.0f} h "
            f"diverged (RMS residual {f.rms_total:.3g} m, at most "
            f"{MAX_FIT_RMS:g} m accepted)"
        )
    # Only a prior from a positive B* is evidence (the element set saw drag); with
    # B* <= 0 it is a starting guess and the floor a fair answer.
    ratio = f.drag_parameter / f.prior if f.prior > 0 else 1.0
    if obj.bstar > 0 and (
        f.drag_parameter <= 1.01 * MIN_DRAG_PARAMETER
        or not 1 / MAX_PRIOR_FACTOR <= ratio <= MAX_PRIOR_FACTOR
    ):
        return ValueError(
            f"the fitted Cd*A/m {f.drag_parameter:.3g} m^2/kg is {ratio:.3g}x its prior "
            f"{f.prior:.3g} m^2/kg (at most {MAX_PRIOR_FACTOR:g}x either way, and above the "
            f"fit's floor of {MIN_DRAG_PARAMETER:g}): not drag, a manoeuvre or thrust?"
        )
    acc = fitted_accuracy(tle_accuracy(f.state))
    return dataclasses.replace(
        obj,
        state=f.state,
        drag_parameter=f.drag_parameter,
        covariance=tle_covariance(f.state, acc) + f.covariance[:6, :6],
        covariance_note=(
            f"{_tle_note(acc)} plus the covariance of the fit to SGP4 over "
            f"{window[0] / 3600:+.0f}..{window[1] / 3600:+.0f} h"
            + (f" of {len(f.element_sets)} element sets" if len(f.element_sets) > 1 else "")
            + f" (RMS residual {f.rms_total:.0f} m"
            + (
                f"; SGP4 debiased by {-f.along_track_bias:+.0f} m along-track"
                if f.along_track_bias
                else ""
            )
            + "); Cd*A/m fitted, "
            f"{f.drag_parameter:.4g} +- {f.drag_sigma:.2g} m^2/kg ({f.prior_note})"
            + _history_note(obj)
        ),
        fit=f,
    )


def _fit_settings(fit: object, deprecated: Mapping[str, object]) -> FitSettings | None:
    """:func:`load`'s ``fit=`` as settings (None: no fit), with the deprecated
    ``model=``, ``span=``, ``threads=``, ``zonal_degree=`` folded in with a warning."""
    loose = dict(deprecated)
    wrong = sorted(set(loose) - set(LoadKeywords.__annotations__))
    if wrong:
        raise TypeError(f"load() got an unexpected keyword argument {wrong[0]!r}")
    if isinstance(fit, FitSettings):
        if loose:
            raise TypeError(
                f"load() got fit=FitSettings(...) and {', '.join(f'{k}=' for k in loose)}; "
                "give the settings in one place"
            )
        return fit
    if not isinstance(fit, (bool, np.bool_)):
        raise TypeError(f"fit must be True, False or a FitSettings, got {type(fit).__name__}")
    given = {k: v for k, v in loose.items() if v is not None}
    if given:
        warnings.warn(
            f"load({', '.join(f'{k}=' for k in given)}) is deprecated; give "
            "fit=rp.catalog.FitSettings(model, span=..., dynamics=rp.Dynamics(zonal_degree="
            "...), threads=...)"
            + ("" if fit else " (without fit=True they did nothing, as before)"),
            DeprecationWarning,
            stacklevel=3,
        )
    if not fit:
        return None
    if given.get("model") is None:
        raise ValueError("a fit needs a density model: load(path, fit=FitSettings(model))")
    degree = given.get("zonal_degree")
    return FitSettings(
        given["model"],  # type: ignore[arg-type]
        span=given.get("span"),  # type: ignore[arg-type]
        dynamics=None if degree is None else Dynamics(zonal_degree=degree),  # type: ignore[arg-type]
        threads=given.get("threads"),  # type: ignore[arg-type]
    )


def _fit_all(
    cat: Catalog,
    settings: FitSettings,
    errors: str,
    history: Mapping[int, Sequence[CatalogObject]] | None = None,
) -> None:
    """Replaces the objects of ``cat`` by fitted ones (in place, order kept) with
    ``settings``, each with its ``history`` of older element sets."""
    import dataclasses

    objs = cat.objects
    assert settings.dynamics is not None  # FitSettings sets it
    fitted = fit_objects(
        objs,
        settings.model,
        span=settings.span,
        threads=settings.threads,
        dynamics=settings.dynamics,
        history=history,
        along_track_bias=settings.along_track_bias,
    )
    kept: list[CatalogObject] = []
    for obj, res in zip(objs, fitted, strict=True):
        if isinstance(res, CatalogObject):
            kept.append(res)
            continue
        message = f"{obj.source}: fit failed: {type(res).__name__}: {res}"
        if obj.bstar > 0:
            kept.append(
                dataclasses.replace(obj, covariance_note=f"{obj.covariance_note}; {message}")
            )
        elif errors == "raise":
            raise ValueError(message) from res
        else:
            cat.skipped.append((obj.source, message))
    cat.objects = kept


def object_error(err: Exception, obj: CatalogObject) -> Exception:
    """``err`` again (same type) with the object named in front, or ``err`` itself when
    its type takes no plain message."""
    try:
        named = type(err)(f"object {obj.norad_id} ({obj.name}, {obj.source}): {err}")
    except Exception:  # an exception type with a different constructor
        return err
    named.__dict__.update(vars(err))  # the core's values (time, axis, ...) stay attributes
    return named


def raise_named(err: Exception, obj: CatalogObject) -> NoReturn:
    """Raises ``err`` with the object named (:func:`object_error`), chained to it."""
    named = object_error(err, obj)
    if named is err:
        raise err
    raise named from err
