"""What the writers of :mod:`rhoprop.io` read from a catalog run, as protocols: the I/O
stage sits below the catalog stage and names no catalog type, so a run of another shape
(a user's own, a subset) writes as long as it has these attributes.
:class:`rhoprop.catalog.CatalogResult` is one."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Protocol

import numpy as np

from ..propagation import OrbitState


class CatalogEntry(Protocol):
    """One object of a run: its name, NORAD id, state at its epoch (``state.epoch`` UTC)
    and Cd*A/m (m^2/kg)."""

    @property
    def name(self) -> str: ...

    @property
    def norad_id(self) -> int: ...

    @property
    def state(self) -> OrbitState: ...

    @property
    def drag_parameter(self) -> float: ...


class CatalogRun(Protocol):
    """A run of many objects on common epochs: ``objects`` (n,), ``epochs`` (nt,)
    datetime64[ns] UTC, ``mean`` (n, nt, 6) m and m/s, ``covariance`` (n, nt, 6, 6),
    ``valid`` (n, nt) bool, and per object ``status``, ``reason``, ``decay_epoch`` and
    ``decay_fraction`` (a ``covariance_note`` per object, when present, says what the
    covariance includes)."""

    @property
    def objects(self) -> Sequence[CatalogEntry]: ...

    @property
    def epochs(self) -> np.ndarray: ...

    @property
    def mean(self) -> np.ndarray: ...

    @property
    def covariance(self) -> np.ndarray: ...

    @property
    def valid(self) -> np.ndarray: ...

    @property
    def status(self) -> np.ndarray: ...

    @property
    def reason(self) -> np.ndarray: ...

    @property
    def decay_epoch(self) -> np.ndarray: ...

    @property
    def decay_fraction(self) -> np.ndarray: ...
