"""The uncertainty methods as objects: :class:`MonteCarlo` (members, each with its own
kappa path) and :class:`Ccsp` (the consider-covariance sigma-point filter). Each is a
frozen record of its settings, checked when it is made, that runs one object
(:meth:`~MonteCarlo.run`) or several (:meth:`~MonteCarlo.run_many`). Every function that
propagates uncertainty (``ensemble``, ``density_pc``, ``propagate_catalog``, the studies,
the CLI) takes one of them as ``method=``; the old strings ``"monte_carlo"`` and
``"ccsp"`` still work for one release and warn (:func:`method_argument`).

This module is the one place that knows the methods apart by name: everything above it
asks the object (docs/architecture.md, "Uncertainty methods")."""

from __future__ import annotations

import warnings
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, fields, replace
from typing import ClassVar, Protocol, TypeAlias, TypeVar, runtime_checkable

import numpy.typing as npt

from .. import _validate
from ..density.model import ModelLike
from ..options import Perturbation
from ..options import UncertaintyMethod as MethodName
from ..time import DurationLike
from .ccsp import (
    CcspRun,
    Coordinates,
    ccsp,
    ccsp_many,
    coordinates_argument,
    interval_times,
    scaling_argument,
)
from .dynamics import Dynamics
from .kappa import KappaProcess
from .montecarlo import (
    MEMBERS,
    OUTPUT_STEP,
    drag_sigma_argument,
    members_argument,
    monte_carlo,
    threads_argument,
)
from .propagate import DEFAULT_MAX_MEMORY
from .results import CcspResult, MonteCarloResult
from .state import OrbitState, Spacecraft

PERTURBATIONS: tuple[Perturbation, ...] = ("additive", "lognormal")


@dataclass(frozen=True)
class Request:
    """One object of :meth:`MonteCarlo.run_many` / :meth:`Ccsp.run_many`: its initial
    ``state`` and ``spacecraft``, the ``duration`` (s, or a ``timedelta``) and an optional
    6x6 ``initial_covariance`` (m^2, m^2/s, m^2/s^2)."""

    state: OrbitState
    spacecraft: Spacecraft
    duration: DurationLike
    initial_covariance: npt.ArrayLike | None = None


@runtime_checkable
class UncertaintyPropagation(Protocol):
    """What every uncertainty method offers: its ``name``, one run and many."""

    name: ClassVar[str]

    def run(
        self,
        state: OrbitState,
        spacecraft: Spacecraft,
        model: ModelLike,
        duration: DurationLike | None = None,
        *,
        initial_covariance: npt.ArrayLike | None = None,
        dynamics: Dynamics | None = None,
    ) -> MonteCarloResult | CcspResult: ...

    def run_many(
        self, requests: Sequence[Request], model: ModelLike, *, dynamics: Dynamics | None = None
    ) -> list[MonteCarloResult | CcspResult | Exception]: ...


def _kappa(value: object) -> None:
    if value is not None and not isinstance(value, KappaProcess):
        raise TypeError(
            f"kappa must be a rhoprop.kappa process or None, got {type(value).__name__}"
        )


def _perturbation(value: object) -> None:
    if value not in PERTURBATIONS:
        raise ValueError(f"perturbation must be 'additive' or 'lognormal', got {value!r}")


@dataclass(frozen=True)
class MonteCarlo:
    """A Monte Carlo of ``n`` members, each with its own density perturbation kappa(t)
    (:func:`rhoprop.monte_carlo`, whose keywords these are).

    Attributes:
        n: members (>= 2).
        seed: seed of the members' random streams (same seed, same numbers, whatever the
            thread count; a catalog's object i runs with ``seed + i``).
        kappa: the kappa process (None: the calibrated :class:`~rhoprop.kappa.TwoScale`).
        output_step: output spacing of a single run, s (None: start and end only).
        perturbation: ``"additive"`` or ``"lognormal"``.
        drag_sigma: relative 1-sigma of Cd*A/m (dimensionless, 0 to 3).
        record_density: also return the density each member sees.
        threads: worker threads of a single run (None: all cores).
        max_memory: limit on a single run's peak memory, bytes.
        progress: True shows a progress bar on a terminal; or a callable, called with
            the members done; False: none.

    Example:
        >>> import rhoprop as rp
        >>> rp.MonteCarlo(n=500, seed=7).n
        500
    """

    n: int = MEMBERS
    seed: int = 0
    kappa: KappaProcess | None = None
    output_step: float | None = OUTPUT_STEP
    perturbation: Perturbation = "additive"
    drag_sigma: float = 0.0
    record_density: bool = False
    threads: int | None = None
    max_memory: float = DEFAULT_MAX_MEMORY
    progress: bool | Callable[[int], object] = True
    name: ClassVar[str] = "monte_carlo"

    def __post_init__(self) -> None:
        object.__setattr__(self, "n", members_argument(self.n))
        object.__setattr__(self, "seed", _validate.seed(self.seed, limit=2**63))
        _kappa(self.kappa)
        if self.output_step is not None:
            object.__setattr__(
                self, "output_step", _validate.positive("output_step", self.output_step)
            )
        _perturbation(self.perturbation)
        object.__setattr__(self, "drag_sigma", drag_sigma_argument(self.drag_sigma))
        if self.threads is not None:
            object.__setattr__(self, "threads", threads_argument(self.threads))
        object.__setattr__(self, "max_memory", _validate.positive("max_memory", self.max_memory))

    def run(
        self,
        state: OrbitState,
        spacecraft: Spacecraft,
        model: ModelLike,
        duration: DurationLike | None = None,
        *,
        initial_covariance: npt.ArrayLike | None = None,
        dynamics: Dynamics | None = None,
    ) -> MonteCarloResult:
        """:func:`rhoprop.monte_carlo` of one object with these settings (``duration``
        s or a ``timedelta``; ``initial_covariance`` 6x6, m^2, m^2/s, m^2/s^2)."""
        return monte_carlo(
            state,
            spacecraft,
            model,
            duration,
            n=self.n,
            kappa=self.kappa,
            seed=self.seed,
            output_step=self.output_step,
            initial_covariance=initial_covariance,
            perturbation=self.perturbation,
            record_density=self.record_density,
            progress=self.progress,
            threads=self.threads,
            max_memory=self.max_memory,
            drag_sigma=self.drag_sigma,
            dynamics=dynamics,
        )

    def run_many(
        self, requests: Sequence[Request], model: ModelLike, *, dynamics: Dynamics | None = None
    ) -> list[MonteCarloResult | CcspResult | Exception]:
        """:meth:`run` of each request in turn (object i with ``seed + i``, as in a
        catalog); a request that fails gives its exception in its place (KeyboardInterrupt
        stops the loop)."""
        reqs = _requests(requests)
        return _one_by_one(lambda i: replace(self, seed=self.seed + i), reqs, model, dynamics)


@dataclass(frozen=True)
class Ccsp:
    """The consider-covariance sigma-point filter (:func:`rhoprop.ccsp`, whose keywords
    these are): density as a consider parameter, mean and covariance propagated together.

    Attributes:
        update_interval: s between updates (None: hourly for a near-circular orbit, once
            per revolution at apogee for an eccentric one; a catalog run updates hourly).
        kappa: the density error the filter stands for (None: the calibrated
            :class:`~rhoprop.kappa.TwoScale`).
        scaling: (lambda1 + n, lambda2 + p); None: from ``kappa`` (the paper's is (3, 3)).
        perturbation: ``"additive"`` or ``"lognormal"``.
        drag_sigma: relative 1-sigma of Cd*A/m (dimensionless, 0 to 3).
        coordinates: ``"equinoctial"`` (default) or ``"cartesian"`` (the paper's).

    Example:
        >>> import rhoprop as rp
        >>> rp.Ccsp(update_interval=1800.0).update_interval
        1800.0
    """

    update_interval: float | None = None
    kappa: KappaProcess | None = None
    scaling: tuple[float, float] | None = None
    perturbation: Perturbation = "additive"
    drag_sigma: float = 0.0
    coordinates: Coordinates = "equinoctial"
    name: ClassVar[str] = "ccsp"

    def __post_init__(self) -> None:
        if self.update_interval is not None:
            object.__setattr__(
                self, "update_interval", _validate.positive("update_interval", self.update_interval)
            )
        _kappa(self.kappa)
        object.__setattr__(self, "scaling", scaling_argument(self.scaling, self.kappa))
        _perturbation(self.perturbation)
        object.__setattr__(self, "drag_sigma", drag_sigma_argument(self.drag_sigma))
        object.__setattr__(self, "coordinates", coordinates_argument(self.coordinates))

    def run(
        self,
        state: OrbitState,
        spacecraft: Spacecraft,
        model: ModelLike,
        duration: DurationLike | None = None,
        *,
        initial_covariance: npt.ArrayLike | None = None,
        dynamics: Dynamics | None = None,
    ) -> CcspResult:
        """:func:`rhoprop.ccsp` of one object with these settings (``duration`` s or a
        ``timedelta``; ``initial_covariance`` 6x6, m^2, m^2/s, m^2/s^2)."""
        return ccsp(
            state,
            spacecraft,
            model,
            duration,
            update_interval=self.update_interval,
            initial_covariance=initial_covariance,
            scaling=self.scaling,
            perturbation=self.perturbation,
            drag_sigma=self.drag_sigma,
            dynamics=dynamics,
            coordinates=self.coordinates,
            kappa=self.kappa,
        )

    def run_many(
        self, requests: Sequence[Request], model: ModelLike, *, dynamics: Dynamics | None = None
    ) -> list[MonteCarloResult | CcspResult | Exception]:
        """The filter of every request in one core call
        (:func:`~rhoprop.propagation.ccsp.ccsp_many`: objects in parallel, each result
        bit for bit :meth:`run` of it alone) when the settings allow (a numeric
        ``update_interval``, the default ``scaling`` and ``perturbation``, automatic
        gravity); else :meth:`run` of each in turn. A request that fails gives its
        exception in its place."""
        reqs = _requests(requests)
        dyn = Dynamics() if dynamics is None else dynamics
        batched = (
            self.update_interval is not None
            and self.scaling is None
            and self.perturbation == "additive"
            and dyn.gravity == (None, None)
            and dyn.integrator in (None, "rk8")
            and dyn.rtol is None
        )
        if not batched:
            return _one_by_one(lambda _i: self, reqs, model, dynamics)
        assert self.update_interval is not None
        out: list[MonteCarloResult | CcspResult | Exception] = []
        runs, where = [], []
        for k, req in enumerate(reqs):
            try:
                _span, times = interval_times(req.duration, self.update_interval)
            except (ValueError, TypeError) as err:
                out.append(err)
                continue
            out.append(ValueError("not run"))  # replaced below
            where.append(k)
            runs.append(
                CcspRun(
                    state=req.state,
                    spacecraft=req.spacecraft,
                    update_times=times,
                    initial_covariance=req.initial_covariance,
                    drag_sigma=self.drag_sigma,
                    step=dyn.step,
                    kappa=self.kappa,
                )
            )
        shared = Dynamics(zonal_degree=dyn.zonal_degree, floor_altitude=dyn.floor_altitude)
        done = ccsp_many(runs, model, dynamics=shared, coordinates=self.coordinates)
        for k, result in zip(where, done, strict=True):
            out[k] = result
        return out


#: A method object (the type of ``method=`` everywhere).
Method: TypeAlias = MonteCarlo | Ccsp
M = TypeVar("M", bound=MonteCarlo | Ccsp)
#: The method classes by name.
_CLASSES: dict[str, type[MonteCarlo] | type[Ccsp]] = {Ccsp.name: Ccsp, MonteCarlo.name: MonteCarlo}
#: The method names (a command line's choices).
NAMES = tuple(_CLASSES)


def _requests(requests: Sequence[Request]) -> list[Request]:
    out = list(requests)
    for k, req in enumerate(out):
        if not isinstance(req, Request):
            raise TypeError(
                f"requests[{k}] must be a rhoprop.propagation.Request, got {type(req).__name__}"
            )
    return out


def _one_by_one(
    method: Callable[[int], MonteCarlo | Ccsp],
    requests: list[Request],
    model: ModelLike,
    dynamics: Dynamics | None,
) -> list[MonteCarloResult | CcspResult | Exception]:
    """Request i run alone by ``method(i)``; a request that fails gives its exception in
    its place (KeyboardInterrupt stops the loop)."""
    out: list[MonteCarloResult | CcspResult | Exception] = []
    for i, req in enumerate(requests):
        try:
            out.append(
                method(i).run(
                    req.state,
                    req.spacecraft,
                    model,
                    req.duration,
                    initial_covariance=req.initial_covariance,
                    dynamics=dynamics,
                )
            )
        except Exception as err:
            out.append(err)
    return out


def method_argument(value: object, function: str, default: Method, stacklevel: int = 3) -> Method:
    """``method=`` of ``function`` as an object: a :class:`MonteCarlo` or :class:`Ccsp`
    as it is; the deprecated strings ``"monte_carlo"`` / ``"ccsp"`` as the function's own
    default of that method (``default`` if it is one, else the class's defaults), with a
    DeprecationWarning; anything else a ValueError/TypeError naming the argument."""
    if isinstance(value, (MonteCarlo, Ccsp)):
        return value
    if isinstance(value, str):
        if value not in _CLASSES:
            raise ValueError(
                f"{function}(): unknown method {value!r}; pass rp.MonteCarlo(...) or rp.Ccsp(...)"
            )
        cls = _CLASSES[value]
        warnings.warn(
            f"{function}(method={value!r}) is deprecated; pass rp.{cls.__name__}(...) "
            "(its settings travel with it)",
            DeprecationWarning,
            stacklevel=stacklevel,
        )
        return default if isinstance(default, cls) else cls()
    raise TypeError(
        f"{function}(): method must be rp.MonteCarlo(...) or rp.Ccsp(...), "
        f"got {type(value).__name__}"
    )


def from_name(name: str, **settings: object) -> Method:
    """The method called ``name`` (``"monte_carlo"`` or ``"ccsp"``: a command line's or a
    scenario file's spelling) with those of ``settings`` it has (None: its default); the
    others belong to the other method and are left out. A ValueError for another name."""
    if name not in _CLASSES:
        raise ValueError(f"unknown method {name!r}; expected 'monte_carlo' or 'ccsp'")
    cls = _CLASSES[name]
    own = {f.name for f in fields(cls)}
    return cls(**{k: v for k, v in settings.items() if k in own and v is not None})  # type: ignore[arg-type]


def with_keywords(method: M, function: str, given: Mapping[str, object], stacklevel: int = 3) -> M:
    """``method`` with the deprecated per-method keywords of ``function`` folded in (those
    not None), with a DeprecationWarning; a keyword the method does not have is a
    TypeError naming it."""
    given = {k: v for k, v in given.items() if v is not None}
    if not given:
        return method
    names = {f.name for f in fields(method)}
    wrong = sorted(set(given) - names)
    if wrong:
        raise TypeError(
            f"{function}(): {', '.join(wrong)} is not a setting of rp.{type(method).__name__}"
        )
    warnings.warn(
        f"{function}({', '.join(f'{k}=' for k in given)}) is deprecated; give them in the "
        f"method: method=rp.{type(method).__name__}({', '.join(f'{k}=...' for k in given)})",
        DeprecationWarning,
        stacklevel=stacklevel,
    )
    return replace(method, **given)  # type: ignore[arg-type]


def require_defaults(method: Method, function: str, names: Sequence[str], instead: str) -> None:
    """ValueError if ``method`` sets one of ``names`` away from its default: ``function``
    has a setting of its own for it (``instead`` says which), and a setting it cannot use
    is refused, never ignored."""
    default = type(method)()
    changed = [n for n in names if getattr(method, n) != getattr(default, n)]
    if changed:
        raise ValueError(
            f"{function}() does not use rp.{type(method).__name__}'s "
            f"{', '.join(changed)} ({instead}); leave {'it' if len(changed) == 1 else 'them'} "
            "at the default"
        )


__all__ = [
    "Ccsp",
    "Method",
    "MethodName",
    "MonteCarlo",
    "Request",
    "UncertaintyPropagation",
    "from_name",
    "method_argument",
    "require_defaults",
    "with_keywords",
]
