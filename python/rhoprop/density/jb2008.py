"""JB2008 (Jacchia-Bowman 2008) through the Rust core, with its index files and an
uncertainty model that grows with geomagnetic activity.

The solar indices come from Space Environment Technologies' ``SOLFSMY.TXT`` (daily F10,
S10, M10, Y10 and their 81-day centred means) and the storm temperature from
``DTCFILE.TXT`` (hourly dTc, K). rhoprop never ships them: pass the two paths to
:class:`Jb2008Indices`, or put both in a directory named by ``$RHOPROP_JB2008_DATA``, or
download them into the user cache with :meth:`Jb2008Indices.refresh`.

Conventions of the reference driver (Bowman 2008, SET release), matched exactly:

* F10/S10 and their means are taken from the record of the day containing t - 1 day, M10
  from t - 2 days, Y10 from t - 5 days; a time at exactly 00:00 UTC belongs to the day it
  starts (the driver's ``INDX = INT(T1950 - FS1950)`` on exact day numbers: the half-open
  day [00:00, 24:00)). An earlier rhoprop took the previous day at 00:00, which moved
  densities at 00:00 by up to 12 % from the reference driver's.
* dTc sits on the hour; the value at t is interpolated linearly between hours and then
  rounded to an integer kelvin (half up).
* The Sun's right ascension/declination and the Greenwich right ascension are the
  reference driver's (Astronomical Almanac low-precision Sun; THETA series in days since
  1950), computed in the core; the point's right ascension is Greenwich angle +
  longitude, and the geodetic latitude is the model latitude, as in the driver.
"""

from __future__ import annotations

import hashlib
import os
import tempfile
import urllib.request
from collections.abc import Callable
from dataclasses import asdict
from pathlib import Path
from typing import Any

import numpy as np

from .. import _core, _validate
from ..cache import cache_dir
from ..errors import OutsideRecordError
from ..spaceweather import SpaceWeather, space_weather_argument
from ..spaceweather.record import (
    AP_RECURRENCE_WEIGHT,
    AP_TARGETS,
    AS_OF_AP_RELAX_DAYS,
    AS_OF_AP_TARGET,
    AS_OF_DAYS,
    recurrence_factor,
)
from ..time import EpochLike, EpochsLike, to_datetime64
from . import calibrated as cal
from .calibrated import Preset
from .correction import MeanCorrection
from .field import FieldResolution, resolution_arg
from .point_model import ActivitySigma, PointModel

#: Where :meth:`Jb2008Indices.refresh` downloads the current files from (SET).
SOLFSMY_URL = "https://sol.spacenvironment.net/JB2008/indices/SOLFSMY.TXT"
DTCFILE_URL = "https://sol.spacenvironment.net/JB2008/indices/DTCFILE.TXT"
#: Environment variable naming a directory holding SOLFSMY.TXT and DTCFILE.TXT.
ENV_VAR = "RHOPROP_JB2008_DATA"
#: Sub-directory of the user cache that :meth:`Jb2008Indices.refresh` writes.
CACHE_SUBDIR = "jb2008"
FILES = ("SOLFSMY.TXT", "DTCFILE.TXT")
#: Lags of F10/S10, M10 and Y10, days.
LAGS = {"F10": 1, "S10": 1, "M10": 2, "Y10": 5}
#: Modified Julian date of the Unix epoch.
_NS_PER_DAY = 86_400 * 10**9
_DAY = np.timedelta64(1, "D")


class Jb2008FileError(ValueError):
    """An index file is missing or malformed; the message names the file and line."""


def _read_daily(
    path: Path,
    what: str,
    layout: str,
    parse: Callable[[list[str]], tuple[int, int, list[float]]],
) -> tuple[np.datetime64, np.ndarray]:
    """(first day, one row of values per day) of an index file whose records are parsed
    by ``parse(fields) -> (year, day of year, values)`` (ValueError or IndexError for a
    malformed one); days must follow one another without gaps. Errors name the file and
    the line."""
    rows: list[list[float]] = []
    first: np.datetime64 | None = None
    expect: np.datetime64 | None = None
    with open(path, encoding="ascii", errors="replace") as f:
        for lineno, line in enumerate(f, 1):
            if not line.strip() or line.lstrip().startswith("#"):
                continue
            try:
                year, doy, values = parse(line.split())
                if not 1 <= doy <= 366:
                    raise ValueError
            except (ValueError, IndexError):
                raise Jb2008FileError(
                    f"{path}, line {lineno}: not a {what} record ({layout}): {line.rstrip()!r}"
                ) from None
            day = np.datetime64(f"{year:04d}-01-01") + np.timedelta64(doy - 1, "D")
            if expect is not None and day != expect:
                raise Jb2008FileError(
                    f"{path}, line {lineno}: day {day} follows {expect - _DAY}; "
                    "the file must have one record per day without gaps"
                )
            if first is None:
                first = day
            expect = day + _DAY
            rows.append(values)
    if first is None:
        raise Jb2008FileError(f"{path}: no {what} records")
    return first, np.array(rows)


def _solfsmy_record(parts: list[str]) -> tuple[int, int, list[float]]:
    values = [float(v) for v in parts[3:11]]
    if len(values) != 8:
        raise ValueError
    return int(parts[0]), int(parts[1]), values


def _dtc_record(parts: list[str]) -> tuple[int, int, list[float]]:
    hours = [float(v) for v in parts[3:27]]
    if parts[0] != "DTC" or len(hours) != 24:
        raise ValueError
    return int(parts[1]), int(parts[2]), hours


def _read_solfsmy(path: Path) -> tuple[np.datetime64, np.ndarray]:
    """(first day, (n, 8) F10, F81c, S10, S81c, M10, M81c, Y10, Y81c) of a SOLFSMY file;
    days must follow one another without gaps."""
    if not path.is_file():
        raise FileNotFoundError(f"JB2008 solar index file not found: {path}")
    layout = "YYYY DDD JulianDay F10 F81c S10 S81c M10 M81c Y10 Y81c"
    return _read_daily(path, "SOLFSMY", layout, _solfsmy_record)


def _read_dtcfile(path: Path) -> tuple[np.datetime64, np.ndarray]:
    """(first hour, hourly dTc K) of a DTCFILE; days must follow one another."""
    if not path.is_file():
        raise FileNotFoundError(f"JB2008 dTc file not found: {path}")
    first, values = _read_daily(path, "DTCFILE", "DTC YYYY DDD and 24 hourly values", _dtc_record)
    return first.astype("datetime64[h]"), values.ravel()


class Jb2008Indices:
    """JB2008 drivers read from Space Environment Technologies' ``SOLFSMY.TXT`` and
    ``DTCFILE.TXT``.

    Args:
        solfsmy: path of ``SOLFSMY.TXT`` (daily F10, S10, M10, Y10 and 81-day means, sfu).
        dtcfile: path of ``DTCFILE.TXT`` (hourly dTc, K).

    Raises FileNotFoundError for a missing file and ValueError naming the file and line
    for a malformed one. :meth:`at` raises :class:`~rhoprop.OutsideRecordError` naming the
    files' span for a time they do not cover.
    """

    def __init__(self, solfsmy: str | os.PathLike[str], dtcfile: str | os.PathLike[str]) -> None:
        self.solfsmy = Path(solfsmy)
        self.dtcfile = Path(dtcfile)
        self._sol_first, self._sol = _read_solfsmy(self.solfsmy)
        self._dtc_first, self._dtc = _read_dtcfile(self.dtcfile)
        self._note = ""

    def __repr__(self) -> str:
        first, last = self.span
        note = f", {self._note}" if self._note else ""
        return (
            f"Jb2008Indices({str(self.solfsmy)!r}, {str(self.dtcfile)!r}; {first} to {last}{note})"
        )

    # -- where the files come from ------------------------------------------------------

    @classmethod
    def locate(cls) -> Jb2008Indices | None:
        """The files in ``$RHOPROP_JB2008_DATA`` if set, else in the user cache
        (``cache_dir()/jb2008``, written by :meth:`refresh`), else None."""
        env = os.environ.get(ENV_VAR)
        if env:
            directory = Path(env).expanduser()
            missing = [name for name in FILES if not (directory / name).is_file()]
            if missing:
                raise FileNotFoundError(
                    f"${ENV_VAR}={env} must be a directory holding {' and '.join(FILES)}; "
                    f"missing {', '.join(missing)}"
                )
            return cls(directory / FILES[0], directory / FILES[1])
        directory = cache_dir() / CACHE_SUBDIR
        if all((directory / name).is_file() for name in FILES):
            return cls(directory / FILES[0], directory / FILES[1])
        return None

    @classmethod
    def default(cls) -> Jb2008Indices:
        """:meth:`locate`, raising FileNotFoundError that says how to get the files."""
        found = cls.locate()
        if found is None:
            raise FileNotFoundError(
                "JB2008 needs Space Environment Technologies' SOLFSMY.TXT and DTCFILE.TXT: "
                f"set ${ENV_VAR} to a directory holding both, pass "
                "rp.density.Jb2008Indices(solfsmy, dtcfile), or run "
                "rp.density.Jb2008Indices.refresh() online to download them into "
                f"{cache_dir() / CACHE_SUBDIR}"
            )
        return found

    @classmethod
    def refresh(
        cls,
        solfsmy_url: str = SOLFSMY_URL,
        dtcfile_url: str = DTCFILE_URL,
        directory: str | os.PathLike[str] | None = None,
        timeout: float = 60.0,
    ) -> Jb2008Indices:
        """Downloads the current files (any ``urllib`` URL, e.g. ``file://``) into
        ``directory`` (default: the user cache, ``cache_dir()/jb2008``) and returns them
        read. Each file is parsed before it replaces the cached copy and is written
        atomically, so a failed download never clobbers good files. ``timeout`` in s."""
        target = Path(directory) if directory is not None else cache_dir() / CACHE_SUBDIR
        target.mkdir(parents=True, exist_ok=True)
        parts: list[Path] = []
        try:
            for url, name, reader in (
                (solfsmy_url, FILES[0], _read_solfsmy),
                (dtcfile_url, FILES[1], _read_dtcfile),
            ):
                request = urllib.request.Request(url, headers={"User-Agent": "rhoprop"})
                with urllib.request.urlopen(request, timeout=timeout) as response:
                    data = response.read()
                handle, tmp = tempfile.mkstemp(dir=target, prefix=f".{name}-", suffix=".part")
                part = Path(tmp)
                parts.append(part)
                with os.fdopen(handle, "wb") as out:
                    out.write(data)
                reader(part)
            for part, name in zip(parts, FILES, strict=True):
                os.replace(part, target / name)
        finally:
            for part in parts:
                part.unlink(missing_ok=True)
        return cls(target / FILES[0], target / FILES[1])

    @classmethod
    def _from_arrays(
        cls,
        source: Jb2008Indices,
        sol_first: np.datetime64,
        sol: np.ndarray,
        dtc_first: np.datetime64,
        dtc: np.ndarray,
        note: str,
    ) -> Jb2008Indices:
        """Indices holding the given arrays, named after ``source``'s files and ``note``."""
        out = cls.__new__(cls)
        out.solfsmy, out.dtcfile = source.solfsmy, source.dtcfile
        out._sol_first, out._sol = sol_first, sol
        out._dtc_first, out._dtc = dtc_first, dtc
        out._note = note
        return out

    def as_of(
        self,
        epoch: EpochLike,
        days: float = AS_OF_DAYS,
        dtc_relax_days: float = AS_OF_AP_RELAX_DAYS,
        dtc_target: str = AS_OF_AP_TARGET,
        recurrence: bool = False,
    ) -> Jb2008Indices:
        """The indices as a forecaster had them at ``epoch`` (UTC), by the rules of
        :meth:`rhoprop.SpaceWeather.as_of` (one forecast rule for every model): the
        solar rows of the days before the epoch's day as observed, then ``days`` days
        (default 60) of persistence of the last observed day's F10, S10, M10 and Y10; the
        81-day centred means whose window reaches past the epoch replaced by each
        index's mean over the last 81 observed days; dTc (K) observed to the epoch's
        hour, then relaxing from it to the last 27 days' level with an e-folding time of
        ``dtc_relax_days`` (default 2 days; ``float("inf")`` holds it), the level being
        ``dtc_target``: the ``"median"`` of the 27 daily means (the default) or the
        ``"mean"`` of the hours, as ``SpaceWeather.as_of`` takes ap's
        (``ap_relax_days``, ``ap_target``). ``recurrence=True`` adds the 27-day
        recurrence as ``SpaceWeather.as_of(recurrence=True)`` does: each daily index
        moved by F10.7's weights of its own change one rotation earlier, dTc's level
        moved linearly towards the days 27 +- 1 before by ap's weight. Nothing after the
        epoch is read. Raises
        :class:`~rhoprop.OutsideRecordError` when the files do not hold the 81 days
        before the epoch."""
        t = to_datetime64(epoch, "epoch")
        if not np.isfinite(days) or not 0 < days <= 366:
            raise ValueError(f"days must be a number of days in (0, 366], got {days!r}")
        if dtc_target not in AP_TARGETS:
            raise ValueError(f"dtc_target must be one of {AP_TARGETS}, got {dtc_target!r}")
        if not isinstance(recurrence, (bool, np.bool_)):
            raise TypeError(f"recurrence must be a bool, got {type(recurrence).__name__}")
        relax_days = (
            np.inf if dtc_relax_days == np.inf else _validate.days("dtc_relax_days", dtc_relax_days)
        )
        day = t.astype("datetime64[D]")
        observed = int((day - self._sol_first).astype(int))  # rows before the epoch's day
        hour = t.astype("datetime64[h]")
        seen = int((hour - self._dtc_first).astype(int)) + 1  # dTc hours up to the epoch's
        if observed < 81 or observed > len(self._sol) or seen < 27 * 24 or seen > len(self._dtc):
            raise OutsideRecordError(
                f"epoch {np.datetime_as_string(t, unit='s')}: the JB2008 index files need "
                f"the 81 observed days before it ({self.solfsmy.name} "
                f"{self._sol_first} + {len(self._sol)} days, {self.dtcfile.name})"
            )
        n_new = int(np.ceil(days)) + 1
        sol = np.empty((observed + n_new, self._sol.shape[1]))
        sol[:observed] = self._sol[:observed]
        past = self._sol[:observed]
        daily, means = (0, 2, 4, 6), (1, 3, 5, 7)
        for d, m in zip(daily, means, strict=True):
            factor = recurrence_factor(past[:, d], observed - 1, n_new) if recurrence else 1.0
            sol[observed:, d] = past[-1, d] * factor
            # Centred 81-day means whose window reaches past the epoch are not known yet.
            sol[observed - 40 :, m] = past[-81:, d].mean()
        dtc_hours = seen + int(24 * n_new)
        dtc = np.empty(dtc_hours)
        dtc[:seen] = self._dtc[:seen]
        last, hours = self._dtc[seen - 1], self._dtc[seen - 27 * 24 : seen]
        # The last 27 days' level as SpaceWeather.as_of takes ap's: the mean, or the
        # median of the daily means.
        month = hours.mean() if dtc_target == "mean" else np.median(hours.reshape(27, 24).mean(1))
        lead_h = np.arange(1, dtc_hours - seen + 1, dtype=float)
        level = np.full(len(lead_h), month)
        if recurrence:
            # Each hour's day one rotation earlier and the days either side, complete
            # days before the epoch's (hours past 25 days ahead keep that day's).
            today = (seen - 1) // 24
            if today < 28:
                raise OutsideRecordError(
                    f"epoch {np.datetime_as_string(t, unit='s')}: the 27-day recurrence needs "
                    f"the 28 days of dTc before the epoch's day ({self.dtcfile.name} starts "
                    f"{self._dtc_first})"
                )
            target = np.minimum((seen - 1 + lead_h.astype(int)) // 24, today + 25)
            days_dtc = self._dtc[: today * 24].reshape(today, 24).mean(1)
            back = target[:, None] - 27 + np.arange(-1, 2)[None, :]
            level = month + AP_RECURRENCE_WEIGHT * (days_dtc[back].mean(1) - month)
        dtc[seen:] = level + (last - level) * np.exp(-lead_h / (24.0 * relax_days))
        stamp = np.datetime_as_string(t, unit="s")
        return Jb2008Indices._from_arrays(
            self, self._sol_first, sol, self._dtc_first, dtc, f"as of {stamp}"
        )

    # -- queries ---------------------------------------------------------------------------

    @property
    def span(self) -> tuple[np.datetime64, np.datetime64]:
        """(first, last) UTC epochs (``datetime64[ns]``) at which every index is defined
        with the reference's lags (5 days after the first solar record, to the last dTc
        hour and one day after the last solar record)."""
        n_sol = len(self._sol)
        # Days are half-open [00:00, 24:00): Y10 (lag 5) exists from 00:00 five days after
        # the first record's day, F10 (lag 1) until just before 00:00 two days after the
        # last record's day.
        one = np.timedelta64(1, "ns")
        first_sol = (self._sol_first + np.timedelta64(5, "D")).astype("datetime64[ns]")
        last_sol = (self._sol_first + np.timedelta64(n_sol + 1, "D")).astype("datetime64[ns]")
        last_sol = last_sol - one
        first_dtc = self._dtc_first.astype("datetime64[ns]")
        last_dtc = (self._dtc_first + np.timedelta64(len(self._dtc) - 1, "h")).astype(
            "datetime64[ns]"
        )
        return max(first_sol, first_dtc), min(last_sol, last_dtc)

    def at(self, times: EpochsLike) -> np.ndarray:
        """The nine JB2008 inputs (n, 9) at UTC ``times`` (n,) datetime64: F10, F10B, S10,
        S10B, M10, M10B, Y10, Y10B (sfu, lagged) and dTc (K, interpolated and rounded)."""
        t = np.asarray(times, dtype="datetime64[ns]").ravel()
        if len(t) == 0:
            return np.zeros((0, 9))
        first, last = self.span
        outside = (t < first) | (t > last)
        if outside.any():
            raise OutsideRecordError(
                f"time {t[outside][0]} is outside the JB2008 index files' span "
                f"{first} to {last} ({self.solfsmy.name}, {self.dtcfile.name})"
            )
        ns = (t - self._sol_first.astype("datetime64[ns]")).astype(np.int64)
        out = np.empty((len(t), 9))
        for lag, cols in ((1, (0, 1, 2, 3)), (2, (4, 5)), (5, (6, 7))):
            row = (ns - lag * _NS_PER_DAY) // _NS_PER_DAY
            out[:, cols] = self._sol[row][:, cols]
        hours = (t - self._dtc_first.astype("datetime64[ns]")).astype(np.int64) / 3.6e12
        k = np.minimum(np.floor(hours).astype(np.int64), len(self._dtc) - 2)
        frac = hours - k
        value = self._dtc[k] + frac * (self._dtc[k + 1] - self._dtc[k])
        out[:, 8] = np.floor(value + 0.5)
        return out

    def mean_dtc(self, first: np.datetime64 | str, last: np.datetime64 | str) -> float:
        """Mean hourly dTc (K) over the days ``first`` to ``last`` (inclusive, UTC dates),
        clipped to the file's span."""
        start = int(self._dtc_first.astype(np.int64))
        a = int(np.asarray(first, dtype="datetime64[h]").astype(np.int64)) - start
        after = np.asarray(last, dtype="datetime64[D]") + _DAY
        b = int(after.astype("datetime64[h]").astype(np.int64)) - start
        a, b = max(a, 0), min(b, len(self._dtc))
        if b <= a:
            raise OutsideRecordError(
                f"{first} to {last} does not overlap the dTc file's span ({self.dtcfile})"
            )
        return float(self._dtc[a:b].mean())

    def digest(self, start: np.datetime64, end: np.datetime64) -> str:
        """SHA-256 of the index values covering [start - 6 days, end + 1 day]."""
        a = (start.astype("datetime64[D]") - self._sol_first).astype(int) - 6
        b = (end.astype("datetime64[D]") - self._sol_first).astype(int) + 2
        h0 = (start.astype("datetime64[h]") - self._dtc_first).astype(int) - 2
        h1 = (end.astype("datetime64[h]") - self._dtc_first).astype(int) + 3
        digest = hashlib.sha256()
        digest.update(np.ascontiguousarray(self._sol[max(a, 0) : max(b, 0)]).tobytes())
        digest.update(np.ascontiguousarray(self._dtc[max(h0, 0) : max(h1, 0)]).tobytes())
        return digest.hexdigest()


#: JB2008's default: 12 % quiet, 27 % in storms (Bruinsma & Boniface 2021: std of
#: observed/model over 28 storms), full at dTc = 150 K (Kp ~ 7, a strong storm).
JB2008_SIGMA = ActivitySigma(quiet=0.12, storm=0.27, full_at=150.0)
#: The calibrated default (``preset="calibrated"``): sigma and mean correction fitted on
#: observed orbit-averaged densities (docs/density-calibration.md).
JB2008_CALIBRATED = (
    ActivitySigma(
        quiet=cal.JB2008_QUIET,
        storm=cal.JB2008_STORM,
        full_at=cal.JB2008_FULL_AT,
        ap_weight=cal.JB2008_AP_WEIGHT,
    ),
    MeanCorrection(cal.JB2008_SCALE, cal.JB2008_F107_EXPONENT),
)


class Jb2008(PointModel):
    """JB2008 mean density (the model's own output) with :class:`ActivitySigma`.

    Args:
        indices: the index files (:class:`Jb2008Indices`); None looks in
            ``$RHOPROP_JB2008_DATA``, then the user cache (FileNotFoundError saying how to
            get them if neither has them).
        uncertainty: :class:`ActivitySigma` in dTc (default: the preset's; the calibrated
            one grows with max(dTc, ``ap_weight`` x ap), 5 K per ap unit).
        correction: :class:`~rhoprop.density.MeanCorrection` (default: the preset's).
        preset: ``"calibrated"`` (default): sigma and mean correction calibrated on
            observed orbit-averaged densities (:data:`JB2008_CALIBRATED`: 0.892 x the model
            x (F10 / F10B) ** -0.319); ``"paper"``: :data:`JB2008_SIGMA` and no correction.
        dtc: None (observed dTc) or a constant dTc (K) used at every time, e.g. its
            long-term mean for the paper's cases III/IV.
        space_weather: the record whose 3-hourly ap enters the sigma when
            ``uncertainty.ap_weight`` > 0 (a :class:`~rhoprop.SpaceWeather`, a path to a
            CelesTrak file, or None: the bundled record). In forecast mode give
            ``SpaceWeather().as_of(epoch)`` beside ``indices.as_of(epoch)``.
        resolution: grid spacing of the sampled field (see :class:`FieldResolution`).

    Example:
        Needs the index files (``$RHOPROP_JB2008_DATA`` or the cache)::

            import numpy as np, rhoprop as rp
            m = rp.density.Jb2008()
            mean, std = m.mean_std(np.datetime64("2002-09-07T12:00"), 10.0, 20.0, 400e3)
    """

    NAME = "JB2008"

    def __init__(
        self,
        indices: Jb2008Indices | None = None,
        uncertainty: ActivitySigma | None = None,
        *,
        correction: MeanCorrection | None = None,
        preset: Preset = "calibrated",
        dtc: float | None = None,
        resolution: FieldResolution | None = None,
        space_weather: SpaceWeather | str | os.PathLike[str] | None = None,
    ) -> None:
        self.indices = Jb2008Indices.default() if indices is None else indices
        if not isinstance(self.indices, Jb2008Indices):
            raise TypeError("indices must be a Jb2008Indices or None")
        self._set_uncertainty(uncertainty, correction, preset, JB2008_SIGMA, JB2008_CALIBRATED)
        self.space_weather = (
            space_weather_argument(space_weather) if self.uncertainty.ap_weight else None
        )
        self.dtc = None if dtc is None else _validate.real("dtc", dtc)
        self.resolution = resolution_arg(resolution)

    def __repr__(self) -> str:
        extra = "" if self.dtc is None else f", dtc={self.dtc:g}"
        return f"Jb2008(uncertainty={self.uncertainty!r}, correction={self.correction!r}{extra})"

    def drivers(self, times: np.ndarray) -> np.ndarray:
        """The (n, 9) inputs at ``times`` (with ``dtc`` substituted when set), and with a
        sigma in ap a tenth column: the 3-hourly ap."""
        ix = self.indices.at(times)
        if self.dtc is not None:
            ix[:, 8] = self.dtc
        if self.space_weather is None:
            return ix
        ap = self.space_weather.drivers(np.asarray(times, dtype="datetime64[ns]").ravel()).ap
        return np.column_stack([ix, ap[:, 1]])

    def _evaluate(
        self,
        mjd: np.ndarray,
        lat: np.ndarray,
        lon: np.ndarray,
        alt: np.ndarray,
        drivers: np.ndarray,
    ) -> np.ndarray:
        inputs = np.ascontiguousarray(drivers[:, :9])
        return np.asarray(_core.jb2008_geodetic(mjd, lat, lon, alt, inputs).density)

    def _activity(self, drivers: np.ndarray) -> np.ndarray:
        if self.space_weather is None:
            return drivers[:, 8]  # dTc, K
        activity: np.ndarray = np.maximum(drivers[:, 8], self.uncertainty.ap_weight * drivers[:, 9])
        return activity

    def _breaks(self, start: np.datetime64, end: np.datetime64) -> np.ndarray:
        days = np.arange(
            start.astype("datetime64[D]"), end.astype("datetime64[D]") + 2, _DAY
        ).astype("datetime64[ns]")
        return days[(days > start) & (days < end)]

    def _grid_values(
        self,
        epochs: np.ndarray,
        left: np.ndarray,
        alt: np.ndarray,
        lat: np.ndarray,
        lon: np.ndarray,
    ) -> tuple[np.ndarray, np.ndarray]:
        """As :meth:`SampledModel._grid_values`, with a node marked ``left`` sampled 1 ns
        before its epoch (the day's indices before a 00:00 jump) and every other node 1 ns
        after (the indices in force over the interval that starts there)."""
        shift = np.where(left, -1, 1).astype("timedelta64[ns]")
        return super()._grid_values(epochs + shift, left, alt, lat, lon)

    def _coverage(self) -> tuple[np.datetime64, np.datetime64] | None:
        if self.space_weather is None:
            return self.indices.span
        (a, b), (c, d) = self.indices.span, self.space_weather.span
        return max(a, c), min(b, d)

    def cache_key(self, start: np.datetime64, end: np.datetime64) -> Any:
        return {
            "model": "jb2008",
            "uncertainty": asdict(self.uncertainty),
            **({} if self.correction.is_identity else {"correction": asdict(self.correction)}),
            "dtc": self.dtc,
            "indices": self.indices.digest(start, end),
            "lags": "midnight-same",
            **({} if self.space_weather is None else {"ap": self._ap_digest(start, end)}),
        }

    def _ap_digest(self, start: np.datetime64, end: np.datetime64) -> str:
        """Digest of the 3-hourly ap from a day before ``start`` to a day after ``end``
        (within the record): what the sigma reads of the record."""
        assert self.space_weather is not None
        first, last = self.space_weather.span
        day = np.timedelta64(1, "D")
        times = np.arange(
            max(start - day, first), min(end + day, last), np.timedelta64(3, "h")
        ).astype("datetime64[ns]")
        ap = self.space_weather.drivers(times).ap[:, 1]
        return hashlib.sha256(np.ascontiguousarray(ap).tobytes()).hexdigest()
