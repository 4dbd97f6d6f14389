"""Conjunction assessment under density uncertainty: close approaches between propagated
objects (``approach``), the probability of collision for Gaussian states, Gaussian
mixtures and Monte Carlo members (``probability``), and CCSDS conjunction data messages
(``cdm``). Positions m, velocities m/s, covariances m^2, hard-body radius m."""

__all__: list[str] = []
