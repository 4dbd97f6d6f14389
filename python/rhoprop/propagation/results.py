"""Results of the propagators: small frozen dataclasses of numpy arrays (SI units,
inertial frame) that share one moments API, :meth:`moments` -> :class:`StateMoments`
(mean state and covariance per output time), so that ensembles, catalogs and exports
treat a trajectory, a Monte Carlo and a CCSP run alike.

Decay: a Monte Carlo member that decayed is NaN in its positions, velocities, RTN errors
and densities from its decay time on, and every statistic here is taken over the members
still flying at each output time (:attr:`MonteCarloResult.survivors`).

Analysis: every result's ``to_xarray()`` gives a labelled ``xarray.Dataset`` (dims epoch,
member, component/state/rtn; units and frame in attributes; docs/analysis.md). The
helpers for those datasets live here too, so that the ensemble and catalog results build
theirs the same way; xarray and pandas are imported only when a dataset is asked for."""

from __future__ import annotations

import importlib
from dataclasses import dataclass, fields
from typing import TYPE_CHECKING, Any

import numpy as np
import numpy.typing as npt
from numpy.typing import NDArray

from .. import _validate, frames
from .._version import __version__
from ..time import EpochLike, offsets_to_epochs, seconds_between, to_datetime64
from .interpolate import DEFAULT_TOLERANCE, interpolate_state
from .kappa import KappaProcess
from .state import OrbitState

if TYPE_CHECKING:
    import xarray

Array = NDArray[Any]

# -- labelled datasets (``to_xarray``; xarray is optional and imported on use) ------------

#: Labels of the ``component`` dimension: a position or velocity vector.
COMPONENTS = ("x", "y", "z")
#: Labels of the ``state`` (and ``state2``) dimension: the six state elements.
STATE_LABELS = ("x", "y", "z", "vx", "vy", "vz")
#: Labels of the ``rtn`` (and ``rtn2``) dimension: radial, along-track, cross-track.
RTN_LABELS = ("R", "T", "N")
#: The ``frame`` attribute of single results: rhoprop's inertial frame (docs/conventions.md,
#: "Frames and dynamics").
#: The ``rtn_frame`` attribute: what the RTN components are taken in.
RTN_FRAME = "RTN of the mean orbit: R = r/|r|, N = r x v/|r x v|, T = N x R"
_STATE_UNITS = "m (x, y, z), m/s (vx, vy, vz)"
_COVARIANCE_UNITS = "m^2, m^2/s, m^2/s^2 (position-position, -velocity, velocity-velocity)"


def optional_import(module: str, what: str) -> Any:
    """The optional package ``module`` (xarray, pandas), or a one-line ImportError naming
    what to install."""
    try:
        return importlib.import_module(module)
    except ImportError:
        raise ImportError(
            f"{what} needs the optional package {module}: pip install {module}"
        ) from None


def iso_utc(epoch: np.datetime64) -> str:
    """``epoch`` as an ISO-8601 UTC string (ns, with a ``Z``)."""
    return f"{np.datetime_as_string(np.asarray(epoch, dtype='datetime64[ns]'))}Z"


def dataset_attrs(
    result_type: str,
    frame: str,
    **extra: object,  # further attributes of any JSON-able type
) -> dict[str, Any]:
    """The attributes every rhoprop dataset carries (netCDF-safe: str, int, float) plus
    ``extra`` (None values left out)."""
    attrs: dict[str, Any] = {
        "title": f"rhoprop {result_type}",
        "source": f"rhoprop {__version__}",
        "rhoprop_version": __version__,
        "result_type": result_type,
        "frame": frame,
        "time_scale": "UTC (epoch coordinates); elapsed seconds are SI, leap seconds counted",
        "units": "SI: m, m/s, s, kg/m^3 (each variable's units attribute)",
    }
    attrs.update({k: v for k, v in extra.items() if v is not None})
    return attrs


def kappa_attrs(process: KappaProcess) -> dict[str, Any]:
    """The kappa process as attributes: ``kappa`` (its kind) and ``kappa_<parameter>``."""
    out: dict[str, Any] = {"kappa": process.kind}
    for f in fields(process):  # type: ignore[arg-type]
        out[f"kappa_{f.name}"] = float(getattr(process, f.name))
    return out


def epoch_coords(epochs: Array, times: Array) -> dict[str, Any]:
    """The ``epoch`` coordinate (datetime64[ns], UTC) and ``elapsed`` (s since the first
    epoch of the run) along it."""
    return {
        "epoch": (
            "epoch",
            np.asarray(epochs, dtype="datetime64[ns]"),
            {"long_name": "output epoch", "time_scale": "UTC"},
        ),
        "elapsed": (
            "epoch",
            np.asarray(times, dtype=float),
            {"units": "s", "long_name": "elapsed SI seconds since initial_epoch"},
        ),
    }


def label_coords(*names: str) -> dict[str, Any]:
    """Label coordinates of the named vector dimensions (component, state, state2, rtn,
    rtn2)."""
    labels = {
        "component": COMPONENTS,
        "state": STATE_LABELS,
        "state2": STATE_LABELS,
        "rtn": RTN_LABELS,
        "rtn2": RTN_LABELS,
    }
    return {name: (name, np.array(labels[name])) for name in names}


def moment_vars(
    lead: tuple[str, ...],
    mean: Array,
    covariance: Array,
    frame: str,
    rtn_covariance: Array | None = None,
) -> dict[str, Any]:
    """Dataset variables of state moments with leading dims ``lead`` (ending in
    ``epoch``): ``mean`` (state), ``covariance`` (state, state2), ``rtn_covariance``
    (rtn, rtn2; RTN of the mean, computed unless given) and ``along_track_std``."""
    m = np.asarray(mean, dtype=float)
    c = np.asarray(covariance, dtype=float)
    if rtn_covariance is None:
        basis = rtn_basis(m[..., :3].reshape(-1, 3), m[..., 3:].reshape(-1, 3))
        pos = c[..., :3, :3].reshape(-1, 3, 3)
        rtn = np.einsum("tij,tjk,tlk->til", basis, pos, basis).reshape((*c.shape[:-2], 3, 3))
    else:
        rtn = np.asarray(rtn_covariance, dtype=float)
    return {
        "mean": ((*lead, "state"), m, {"units": _STATE_UNITS, "frame": frame}),
        "covariance": (
            (*lead, "state", "state2"),
            c,
            {"units": _COVARIANCE_UNITS, "frame": frame},
        ),
        "rtn_covariance": (
            (*lead, "rtn", "rtn2"),
            rtn,
            {"units": "m^2", "long_name": "position covariance", "frame": RTN_FRAME},
        ),
        "along_track_std": (
            lead,
            np.sqrt(rtn[..., 1, 1]),
            {"units": "m", "long_name": "along-track standard deviation", "frame": RTN_FRAME},
        ),
    }


def _vector(dims: tuple[str, ...], values: Array, units: str, name: str, frame: str) -> Any:
    return (
        dims,
        np.asarray(values, dtype=float),
        {"units": units, "long_name": name, "frame": frame},
    )


def _padded(values: Array, nt: int) -> Array:
    """``values`` (k, ...) on ``nt`` rows, NaN past its end."""
    out = np.full((nt, *np.shape(values)[1:]), np.nan)
    out[: len(values)] = values
    return out


@dataclass(frozen=True)
class StateMoments:
    """Mean and covariance of the state at each output time.

    Attributes:
        epoch: initial epoch (UTC).
        times: output times, s from ``epoch`` (nt,).
        mean: mean state (nt, 6), m and m/s, in ``frame``.
        covariance: state covariance (nt, 6, 6), m^2, m^2/s, m^2/s^2.
        count: for a Monte Carlo, the number of members behind each time's statistics
            (the survivors, (nt,)); None for a filter or a single trajectory. Where fewer
            than two members remain the covariance is NaN (and the mean too where none
            does).
        frame: the frame of ``mean`` and ``covariance``.
    """

    epoch: np.datetime64
    times: Array
    mean: Array
    covariance: Array
    count: Array | None = None
    frame: str = "GCRF"

    def at(
        self, at: EpochLike, *, tolerance: float = DEFAULT_TOLERANCE
    ) -> tuple[OrbitState, Array]:
        """The mean state and the covariance (6, 6) at the UTC epoch ``at``: an output's
        own, else the mean interpolated by a degree-7 Hermite polynomial (as
        :meth:`Trajectory.state_at`, checked to ``tolerance`` m) and the covariance
        interpolated linearly between the two outputs around it in the RTN frame of
        their means (position and velocity blocks alike), then turned into the
        interpolated mean's axes: the covariance's growth and its turn with the orbit
        are kept, what changes faster than the output spacing is not. A ValueError
        where the mean cannot be interpolated (outside the outputs, too far apart, next
        to a decay) or the covariance is NaN."""
        epoch = to_datetime64(at, "at")
        tol = _validate.positive("tolerance", tolerance)
        t = seconds_between(self.epoch, epoch)
        try:
            r, v = interpolate_state(self.times, self.mean[:, :3], self.mean[:, 3:], t, tol)
        except ValueError as err:
            raise ValueError(f"moments at {epoch}: {err}") from None
        hi = int(np.clip(np.searchsorted(self.times, t), 1, len(self.times) - 1))
        lo = hi - 1
        f = float(np.clip((t - self.times[lo]) / (self.times[hi] - self.times[lo]), 0.0, 1.0))
        big = np.zeros((2, 6, 6))
        big[:, :3, :3] = big[:, 3:, 3:] = rtn_basis(
            self.mean[[lo, hi], :3], self.mean[[lo, hi], 3:]
        )
        rtn = big @ self.covariance[[lo, hi]] @ np.swapaxes(big, 1, 2)
        here = np.zeros((6, 6))
        here[:3, :3] = here[3:, 3:] = frames.rtn_basis(r, v)
        cov = here.T @ ((1.0 - f) * rtn[0] + f * rtn[1]) @ here
        if not np.isfinite(cov).all():
            raise ValueError(f"moments at {epoch}: no covariance there (NaN)")
        return OrbitState(epoch, r, v, self.frame), (cov + cov.T) / 2.0

    @property
    def epochs(self) -> Array:
        """Output epochs, datetime64[ns] (nt,)."""
        return offsets_to_epochs(self.epoch, self.times)

    @property
    def rtn_covariance(self) -> Array:
        """Position covariance in the RTN frame of the mean (nt, 3, 3), m^2 (NaN where the
        mean is)."""
        basis = rtn_basis(self.mean[:, :3], self.mean[:, 3:])
        return np.asarray(np.einsum("tij,tjk,tlk->til", basis, self.covariance[:, :3, :3], basis))

    @property
    def along_track_std(self) -> Array:
        """Square root of the along-track variance (nt,), m."""
        return np.asarray(np.sqrt(self.rtn_covariance[:, 1, 1]))

    def position_in_frame(
        self, ref_positions: npt.ArrayLike, ref_velocities: npt.ArrayLike
    ) -> tuple[Array, Array]:
        """Mean position offset from a reference orbit (nt, 3) and the position covariance
        (nt, 3, 3), both in the reference orbit's RTN frame, m and m^2."""
        ref_p = np.asarray(ref_positions, dtype=float)
        basis = rtn_basis(ref_p, ref_velocities)
        means = np.einsum("tij,tj->ti", basis, self.mean[:, :3] - ref_p)
        covs = np.einsum("tij,tjk,tlk->til", basis, self.covariance[:, :3, :3], basis)
        return means, covs


def rtn_basis(positions: npt.ArrayLike, velocities: npt.ArrayLike) -> Array:
    """RTN bases (nt, 3, 3) of reference states (nt, 3) that may hold NaN rows (a decayed
    reference): those rows give a NaN basis instead of an error."""
    p = np.asarray(positions, dtype=float).reshape(-1, 3)
    v = np.asarray(velocities, dtype=float).reshape(-1, 3)
    ok = np.isfinite(p).all(axis=1) & np.isfinite(v).all(axis=1)
    out = np.full((len(p), 3, 3), np.nan)
    if ok.any():
        out[ok] = frames.rtn_basis(p[ok], v[ok]).reshape(-1, 3, 3)
    return out


def sample_moments(states: np.ndarray, alive: np.ndarray | None = None) -> tuple[Array, Array]:
    """Sample mean (nt, k) and covariance (nt, k, k), ddof = 1, of member values
    (n, nt, k) (states: k = 6), over the members ``alive`` (n, nt) at each time (default:
    those with finite values, so decayed members, NaN after their decay, are left out).
    The mean is NaN where no member is alive, the covariance where fewer than two are."""
    s = np.asarray(states, dtype=float)
    ok = np.isfinite(s).all(axis=2) if alive is None else np.asarray(alive, dtype=bool)
    count = ok.sum(axis=0)  # (nt,)
    w = ok[..., None].astype(float)
    values = np.where(ok[..., None], s, 0.0)
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = (w * values).sum(axis=0) / count[:, None]
        d = np.where(ok[..., None], values - mean[None], 0.0)
        cov = np.einsum("nti,ntj->tij", d, d) / (count - 1)[:, None, None]
    mean[count == 0] = np.nan
    cov[count < 2] = np.nan
    return mean, cov


@dataclass(frozen=True)
class Trajectory:
    """A propagated trajectory.

    Attributes:
        epoch: initial epoch (UTC, ``datetime64[ns]``).
        times: output times, s from ``epoch``, float64 (nt,).
        positions: inertial positions (nt, 3), m.
        velocities: inertial velocities (nt, 3), m/s.
        decayed_at: time (s from ``epoch``) at which the object went below the floor
            altitude, or None. Outputs stop before it.
        evaluations: number of right-hand-side evaluations.
        clipped: number of density evaluations clipped at zero.
        frame: the frame of the states, the initial state's (one of
            :data:`rhoprop.frames.INERTIAL_FRAMES`).
    """

    epoch: np.datetime64
    times: Array
    positions: Array
    velocities: Array
    decayed_at: float | None = None
    evaluations: int = 0
    clipped: int = 0
    frame: str = "GCRF"

    @property
    def epochs(self) -> Array:
        """Output epochs, ``datetime64[ns]`` (nt,)."""
        return offsets_to_epochs(self.epoch, self.times)

    @property
    def states(self) -> Array:
        """States (nt, 6): position m, velocity m/s."""
        return np.concatenate([self.positions, self.velocities], axis=1)

    def state_at(
        self, at: int | EpochLike = -1, *, tolerance: float = DEFAULT_TOLERANCE
    ) -> OrbitState:
        """The state at output index ``at`` (an integer, default the last), or at the UTC
        epoch ``at`` (an output's own state, else interpolated between the outputs by a
        degree-7 Hermite polynomial, :mod:`rhoprop.propagation.interpolate`). An epoch
        outside the outputs, next to a decayed one, or where the outputs are too far apart
        to interpolate to ``tolerance`` m (twice the difference of the fits of degree 7 and
        9 exceeds it) is a ValueError saying so."""
        if isinstance(at, bool):
            raise TypeError("at must be an output index or a UTC epoch, got a bool")
        if isinstance(at, (int, np.integer)):
            return OrbitState(self.epochs[at], self.positions[at], self.velocities[at], self.frame)
        epoch = to_datetime64(at, "at")
        tol = _validate.positive("tolerance", tolerance)
        t = seconds_between(self.epoch, epoch)
        try:
            r, v = interpolate_state(self.times, self.positions, self.velocities, t, tol)
        except ValueError as err:
            raise ValueError(f"state_at({epoch}): {err}") from None
        return OrbitState(epoch, r, v, self.frame)

    def moments(self) -> StateMoments:
        """The states with zero covariance (a deterministic orbit)."""
        zero = np.zeros((len(self.times), 6, 6))
        return StateMoments(self.epoch, self.times, self.states, zero, frame=self.frame)

    def to_xarray(self) -> xarray.Dataset:
        """The trajectory as an ``xarray.Dataset`` (needs the ``[xarray]`` extra).

        Dims ``epoch`` (datetime64[ns] UTC coordinate, with ``elapsed`` s) and
        ``component`` (x, y, z); variables ``position`` (m) and ``velocity`` (m/s),
        inertial; attributes: frame, units, ``initial_epoch``, ``decayed_at_s`` (NaN:
        no decay), ``evaluations``, ``clipped`` and the rhoprop version.
        """
        xr = optional_import("xarray", "Trajectory.to_xarray()")
        dims = ("epoch", "component")
        ds: xarray.Dataset = xr.Dataset(
            {
                "position": _vector(dims, self.positions, "m", "position", self.frame),
                "velocity": _vector(dims, self.velocities, "m/s", "velocity", self.frame),
            },
            coords={**epoch_coords(self.epochs, self.times), **label_coords("component")},
            attrs=dataset_attrs(
                "Trajectory",
                self.frame,
                initial_epoch=iso_utc(self.epoch),
                decayed_at_s=np.nan if self.decayed_at is None else float(self.decayed_at),
                evaluations=int(self.evaluations),
                clipped=int(self.clipped),
            ),
        )
        return ds


def trajectory_from_core(
    epoch: np.datetime64, out: tuple[Any, ...], frame: str = "GCRF"
) -> Trajectory:
    """A :class:`Trajectory` in ``frame`` from the tuple ``core_propagate`` returns."""
    t, states, decayed_at, evaluations, clipped = out
    return Trajectory(
        frame=frame,
        epoch=epoch,
        times=t,
        positions=states[:, :3],
        velocities=states[:, 3:],
        decayed_at=decayed_at,
        evaluations=int(evaluations),
        clipped=int(clipped),
    )


@dataclass(frozen=True)
class RtnStats:
    """Per output time: mean and standard deviation (ddof = 1) of the RTN errors over the
    surviving members, m (nt, 3) each, and their number ``count`` (nt,). NaN where fewer
    than two members (mean: none) survive."""

    mean: Array
    std: Array
    count: Array


@dataclass(frozen=True)
class MonteCarloResult:
    """An ensemble of members propagated with their own density perturbation.

    Decayed members: a member that went below the floor altitude at ``decay_times[i]`` is
    NaN in ``positions``, ``velocities``, ``rtn_errors`` and ``densities`` at every output
    time at or after its decay (``alive`` is False there); :meth:`stats`, :meth:`moments`
    and everything built on them use the members still flying, counted per output time
    by :attr:`survivors`. Plain numpy reductions over the member axis therefore give NaN
    once a member has decayed: use ``np.nanstd`` or :meth:`stats`.

    Attributes:
        epoch: initial epoch (UTC).
        times: output times, s from ``epoch`` (nt,).
        positions: member positions (n, nt, 3), m, inertial (NaN after decay).
        velocities: member velocities (n, nt, 3), m/s (NaN after decay).
        mean_orbit: the orbit at the mean density (kappa = 0), same integrator and step;
            shorter than ``times`` if it decayed (``mean_orbit.decayed_at``).
        rtn_errors: member position minus the reference position, in the reference's RTN
            frame (n, nt, 3), m (NaN after the member's decay).
        clipped: density evaluations clipped at zero per member (additive form) (n,).
        decay_times: decay time per member, s from ``epoch`` (inf: no decay) (n,).
        densities: density each member saw at the output times (n, nt), kg/m^3, or None.
        kappa: the kappa process; seed: the seed; step: the integration step used, s.
        reference_positions, reference_velocities: the reference of ``rtn_errors``
            (nt, 3), m and m/s: the mean orbit while it flies; after the mean orbit's
            decay, the sample mean of the surviving members (NaN once none survives).
        drag_sigma: relative 1-sigma of Cd*A/m the members were drawn with (0: none).
        drag_factors: factor on Cd*A/m of each member (n,), exp(drag_sigma c) with
            c ~ N(0, 1) (all 1 when ``drag_sigma`` is 0); None for results built by hand.
        frame: the frame of positions, velocities and the reference, the initial
            state's (:data:`rhoprop.frames.INERTIAL_FRAMES`).
    """

    epoch: np.datetime64
    times: Array
    positions: Array
    velocities: Array
    mean_orbit: Trajectory
    rtn_errors: Array
    clipped: Array
    decay_times: Array
    densities: Array | None
    kappa: KappaProcess
    seed: int
    step: float
    reference_positions: Array
    reference_velocities: Array
    drag_sigma: float = 0.0
    drag_factors: Array | None = None
    frame: str = "GCRF"

    @property
    def epochs(self) -> Array:
        """Output epochs, datetime64[ns] (nt,)."""
        return offsets_to_epochs(self.epoch, self.times)

    @property
    def along_track(self) -> Array:
        """Along-track error of each member (n, nt), m: position difference projected on T
        (NaN after the member's decay)."""
        return self.rtn_errors[..., 1]

    @property
    def decayed(self) -> Array:
        """Whether each member decayed below the floor altitude (n,)."""
        return np.isfinite(self.decay_times)

    @property
    def alive(self) -> Array:
        """Whether each member is still flying at each output time (n, nt): the output
        time is before its decay time."""
        return np.asarray(self.times[None, :] < self.decay_times[:, None])

    @property
    def survivors(self) -> Array:
        """Number of members still flying at each output time (nt,)."""
        return np.asarray(self.alive.sum(axis=0))

    def along_track_curvilinear(self) -> Array:
        """Curvilinear along-track error (n, nt), m: r_ref times the angle between the
        member and the reference position within the reference orbit's plane."""
        basis = rtn_basis(self.reference_positions, self.reference_velocities)
        radial = np.einsum("tj,ntj->nt", basis[:, 0], self.positions)
        along = np.einsum("tj,ntj->nt", basis[:, 1], self.positions)
        r_ref = np.linalg.norm(self.reference_positions, axis=1)
        return np.asarray(r_ref * np.arctan2(along, radial))

    def stats(self) -> RtnStats:
        """Mean and standard deviation (ddof = 1) of the RTN errors per output time, over
        the members still flying then."""
        mean, cov = sample_moments(self.rtn_errors, self.alive)
        std = np.sqrt(np.diagonal(cov, axis1=1, axis2=2))
        return RtnStats(mean, std, self.survivors)

    def moments(self) -> StateMoments:
        """Sample mean and covariance (ddof = 1) of the surviving members' states, with
        their number per time (``count``)."""
        alive = self.alive
        mean, cov = sample_moments(np.concatenate([self.positions, self.velocities], axis=2), alive)
        return StateMoments(self.epoch, self.times, mean, cov, alive.sum(axis=0), self.frame)

    def moments_at(
        self, at: EpochLike, *, tolerance: float = DEFAULT_TOLERANCE
    ) -> tuple[OrbitState, Array]:
        """The members' mean state and covariance (6, 6) at the UTC epoch ``at``,
        interpolated between the outputs (:meth:`StateMoments.at`)."""
        return self.moments().at(at, tolerance=tolerance)

    def to_xarray(self, *, members: bool = True) -> xarray.Dataset:
        """The ensemble as an ``xarray.Dataset`` (needs the ``[xarray]`` extra).

        Dims ``member``, ``epoch`` (datetime64[ns] UTC coordinate, with ``elapsed`` s),
        ``component`` (x, y, z), ``rtn`` (R, T, N), ``state``/``state2`` (x ... vz).
        Per member (left out with ``members=False``): ``position`` (m), ``velocity``
        (m/s), ``rtn_error`` (m, RTN of the reference), ``along_track_curvilinear`` (m),
        ``density`` (kg/m^3, when recorded), ``alive``. Per member: ``decay_time`` (s,
        inf: none), ``clipped``. Per epoch: ``survivors``, the ``reference_*`` and
        ``mean_orbit_*`` positions and velocities, the RTN statistics ``rtn_mean`` and
        ``rtn_std`` (over the members flying) and the moments ``mean``, ``covariance``,
        ``rtn_covariance``, ``along_track_std``. Attributes: frame, units, kappa process,
        seed, step, initial epoch, rhoprop version. NaN after a member's decay, as here.
        """
        xr = optional_import("xarray", "MonteCarloResult.to_xarray()")
        nt = len(self.times)
        stats = self.stats()
        moments = self.moments()
        vec = ("epoch", "component")
        data: dict[str, Any] = {}
        if members:
            mvec = ("member", "epoch", "component")
            data["position"] = _vector(mvec, self.positions, "m", "position", self.frame)
            data["velocity"] = _vector(mvec, self.velocities, "m/s", "velocity", self.frame)
            data["rtn_error"] = (
                ("member", "epoch", "rtn"),
                np.asarray(self.rtn_errors, dtype=float),
                {
                    "units": "m",
                    "long_name": "position minus the reference position",
                    "frame": "RTN of the reference orbit (reference_position/velocity)",
                },
            )
            data["along_track_curvilinear"] = (
                ("member", "epoch"),
                self.along_track_curvilinear(),
                {"units": "m", "long_name": "r_ref times the along-track angle"},
            )
            if self.densities is not None:
                data["density"] = (
                    ("member", "epoch"),
                    np.asarray(self.densities, dtype=float),
                    {"units": "kg/m^3", "long_name": "density seen by the member"},
                )
            data["alive"] = (("member", "epoch"), self.alive, {"long_name": "still flying"})
        data["decay_time"] = (
            "member",
            np.asarray(self.decay_times, dtype=float),
            {"units": "s", "long_name": "decay time since initial_epoch (inf: none)"},
        )
        data["clipped"] = (
            "member",
            np.asarray(self.clipped, dtype=np.int64),
            {"long_name": "density evaluations clipped at zero"},
        )
        if self.drag_factors is not None:
            data["drag_factor"] = (
                "member",
                np.asarray(self.drag_factors, dtype=float),
                {"units": "1", "long_name": "factor on Cd*A/m of the member (see drag_sigma)"},
            )
        data["survivors"] = ("epoch", self.survivors, {"long_name": "members still flying"})
        for name, values, units in (
            ("reference_position", self.reference_positions, "m"),
            ("reference_velocity", self.reference_velocities, "m/s"),
            ("mean_orbit_position", _padded(self.mean_orbit.positions, nt), "m"),
            ("mean_orbit_velocity", _padded(self.mean_orbit.velocities, nt), "m/s"),
        ):
            data[name] = _vector(vec, values, units, name.replace("_", " "), self.frame)
        rtn_attrs = {"units": "m", "frame": "RTN of the reference orbit"}
        data["rtn_mean"] = (("epoch", "rtn"), stats.mean, rtn_attrs)
        data["rtn_std"] = (("epoch", "rtn"), stats.std, {**rtn_attrs, "ddof": 1})
        data.update(moment_vars(("epoch",), moments.mean, moments.covariance, self.frame))
        ds: xarray.Dataset = xr.Dataset(
            data,
            coords={
                **epoch_coords(self.epochs, self.times),
                "member": ("member", np.arange(len(self.decay_times))),
                **label_coords("component", "rtn", "rtn2", "state", "state2"),
            },
            attrs=dataset_attrs(
                "MonteCarloResult",
                self.frame,
                rtn_frame=RTN_FRAME,
                initial_epoch=iso_utc(self.epoch),
                members=len(self.decay_times),
                **kappa_attrs(self.kappa),
                seed=int(self.seed),
                step_s=float(self.step),
                drag_sigma=float(self.drag_sigma),
                mean_orbit_decayed_at_s=np.nan
                if self.mean_orbit.decayed_at is None
                else float(self.mean_orbit.decayed_at),
            ),
        )
        return ds


@dataclass(frozen=True)
class CcspResult:
    """CCSP outputs at every update time.

    Attributes:
        epoch: initial epoch (UTC).
        times: update times, s from ``epoch`` (nt,), starting at 0.
        mean: mean state (nt, 6), m and m/s, in ``frame``.
        covariance: state covariance (nt, 6, 6), SI units, in ``frame``.
        rtn_covariance: position covariance in the RTN frame of the mean (nt, 3, 3), m^2.
        along_track_std: sqrt of the along-track variance (nt,), m.
        cross_covariance: covariance of the state with the normalised density offset kappa
            (nt, 6), m and m/s.
        decayed_at: None, or the time (s from ``epoch``) at which a sigma point first went
            below the floor altitude: the filter stopped there and the outputs end at the
            last update completed before it.
        drag_sigma: relative 1-sigma of Cd*A/m carried as the second consider parameter
            (0: density only, the paper's filter).
        drag_cross_covariance: covariance of the state with the normalised
            ballistic-coefficient error c (nt, 6), m and m/s (zero when ``drag_sigma`` is
            0); None for results built by hand.
        element_mean: the filter's own mean in equinoctial elements (nt, 6): a (m, the
            energy semi-major axis, free of the J2 swing), h, k, p, q, lambda (rad, in
            (-pi, pi]), in the axes of :func:`rhoprop.frames.to_equinoctial` (with
            ``semi_major="energy"``) with ``reference`` as reference, in the axes the
            run integrated in (TEME of the initial epoch:
            :mod:`rhoprop.propagation.run_frame`; :meth:`to_elements` takes states of
            ``frame`` there, :meth:`from_elements` back); None for Cartesian runs
            (``coordinates="cartesian"``).
        element_covariance: the filter's covariance in those elements (nt, 6, 6): the
            Gaussian that holds for weeks (``covariance`` is its linear map to Cartesian
            coordinates, which past about a week misses the along-track curvature);
            None for Cartesian runs.
        reference: the initial state (6,) in the axes the run integrated in (equal to
            the initial state for a TEME one), whose axes the elements are in; None for
            results built by hand.
        frame: the frame of ``mean``, ``covariance`` and the cross-covariances, the
            initial state's (:data:`rhoprop.frames.INERTIAL_FRAMES`).
    """

    epoch: np.datetime64
    times: Array
    mean: Array
    covariance: Array
    rtn_covariance: Array
    along_track_std: Array
    cross_covariance: Array
    decayed_at: float | None = None
    drag_sigma: float = 0.0
    drag_cross_covariance: Array | None = None
    element_mean: Array | None = None
    element_covariance: Array | None = None
    reference: Array | None = None
    frame: str = "GCRF"

    @property
    def epochs(self) -> Array:
        """Update epochs, datetime64[ns] (nt,)."""
        return offsets_to_epochs(self.epoch, self.times)

    def _run_axes(self) -> Array:
        """The rotation from the axes the run integrated in (TEME of the initial epoch)
        to ``frame``'s (the identity for TEME)."""
        if self.frame == "TEME":
            return np.eye(3)
        return frames.teme_to_gcrf_matrix(self.epoch)

    def to_elements(self, states: npt.ArrayLike) -> Array:
        """States (6,) or (n, 6) in ``frame``, m and m/s, as the filter's equinoctial
        elements (energy semi-major axis, the axes of ``reference``): comparable with
        ``element_mean`` and ``element_covariance``, e.g. a Monte Carlo's members."""
        x = np.asarray(states, dtype=float)
        if self.reference is None:
            raise ValueError("a result built by hand has no reference axes for elements")
        rot = self._run_axes()
        inside = np.concatenate([x[..., :3] @ rot, x[..., 3:] @ rot], axis=-1)
        return frames.to_equinoctial(inside, self.reference, semi_major="energy")

    def from_elements(self, elements: npt.ArrayLike) -> Array:
        """The filter's equinoctial elements (6,) or (n, 6) back to states in ``frame``
        (the inverse of :meth:`to_elements`)."""
        if self.reference is None:
            raise ValueError("a result built by hand has no reference axes for elements")
        x = frames.from_equinoctial(elements, self.reference, semi_major="energy")
        rot = self._run_axes()
        return np.concatenate([x[..., :3] @ rot.T, x[..., 3:] @ rot.T], axis=-1)

    def arc_sag_share(self) -> Array:
        """Per output (nt,), the along-track arc's radial sag over the radial 1-sigma
        (:func:`~rhoprop.propagation.gaussian_check.arc_sag_share`): from 0.5 on, the
        Cartesian ``covariance`` no longer holds the spread's curved shape (its moments
        stay right; use ``element_covariance`` or a Monte Carlo for the shape;
        docs/mc-vs-ccsp.md, "Every run knows"). NaN for Cartesian runs."""
        from .gaussian_check import arc_sag_share

        if self.element_mean is None or self.element_covariance is None:
            return np.full(len(self.times), np.nan)
        return arc_sag_share(self.element_mean, self.element_covariance, self.rtn_covariance)

    def moments(self) -> StateMoments:
        """The filter's mean and covariance."""
        return StateMoments(self.epoch, self.times, self.mean, self.covariance, frame=self.frame)

    def moments_at(
        self, at: EpochLike, *, tolerance: float = DEFAULT_TOLERANCE
    ) -> tuple[OrbitState, Array]:
        """The mean state and covariance (6, 6) at the UTC epoch ``at``, interpolated
        between the outputs (:meth:`StateMoments.at`)."""
        return self.moments().at(at, tolerance=tolerance)

    def to_xarray(self) -> xarray.Dataset:
        """The filter's outputs as an ``xarray.Dataset`` (needs the ``[xarray]`` extra).

        Dims ``epoch`` (update epochs, datetime64[ns] UTC, with ``elapsed`` s),
        ``state``/``state2`` (x ... vz), ``rtn``/``rtn2`` (R, T, N); variables ``mean``,
        ``covariance``, ``rtn_covariance``, ``along_track_std`` and ``cross_covariance``
        (state with kappa); attributes: frame, units, ``initial_epoch``,
        ``decayed_at_s`` (NaN: the filter ran to the end), rhoprop version.
        """
        xr = optional_import("xarray", "CcspResult.to_xarray()")
        data = moment_vars(("epoch",), self.mean, self.covariance, self.frame, self.rtn_covariance)
        data["cross_covariance"] = _cross_covariance_var(
            self.cross_covariance, "the normalised density offset kappa", self.frame
        )
        if self.drag_cross_covariance is not None:
            data["drag_cross_covariance"] = _cross_covariance_var(
                self.drag_cross_covariance, "the normalised Cd*A/m error", self.frame
            )
        ds: xarray.Dataset = xr.Dataset(
            data,
            coords={
                **epoch_coords(self.epochs, self.times),
                **label_coords("state", "state2", "rtn", "rtn2"),
            },
            attrs=dataset_attrs(
                "CcspResult",
                self.frame,
                rtn_frame=RTN_FRAME,
                initial_epoch=iso_utc(self.epoch),
                decayed_at_s=np.nan if self.decayed_at is None else float(self.decayed_at),
                drag_sigma=float(self.drag_sigma),
            ),
        )
        return ds


def _cross_covariance_var(values: Any, with_what: str, frame: str) -> tuple[Any, ...]:
    """An xarray variable (dims, values, attributes) of the state's covariance with a
    consider parameter, per epoch."""
    return (
        ("epoch", "state"),
        np.asarray(values, dtype=float),
        {
            "units": "m (x, y, z), m/s (vx, vy, vz)",
            "long_name": f"covariance of the state with {with_what}",
            "frame": frame,
        },
    )
