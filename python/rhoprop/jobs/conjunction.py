"""``rhoprop conjunction``: one CDM's Pc with the density models' disagreement added."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from ..conjunction.with_density import DensityPc
from ..propagation.methods import Ccsp, Method

__all__ = ["ConjunctionJob"]


@dataclass(frozen=True)
class ConjunctionJob:
    """The ``rhoprop conjunction`` job: a CDM's Pc with the default density-model families
    added (:func:`rhoprop.conjunction.density_pc`), printed as a table and optionally
    written as JSON. Space weather: the cached record (``rhoprop data refresh``) with its
    predictions as forecast drivers, else the bundled one."""

    path: str | Path
    hard_body_radius: float | None = None
    lead_time: float | None = None
    method: Method = Ccsp()
    drag_parameters: tuple[float | None, float | None] = (None, None)
    json_path: str | Path | None = None

    def run(self) -> DensityPc:
        """Runs the job (see the class). Returns the Pc with density uncertainty."""
        import json

        from ..conjunction import density_pc, read_cdm
        from ..spaceweather import SpaceWeather
        from ..studies.scenarios import REFERENCE_MODEL, default_models, model_choice

        message = read_cdm(self.path)
        names, reason, _ = model_choice()
        print(f"{message.object1.name} x {message.object2.name}, TCA {str(message.tca)[:23]} UTC")
        print(f"models: {', '.join(names)}: {reason}")
        models = default_models(SpaceWeather.cached().with_forecast())
        result = density_pc(
            message,
            models,
            REFERENCE_MODEL,
            hard_body_radius=self.hard_body_radius,
            lead_time=self.lead_time,
            drag_parameters=self.drag_parameters,
            method=self.method,
        )
        if message.collision_probability is not None:
            print(f"Pc stated in the message: {message.collision_probability:.4g}")
        print(
            f"density uncertainty from {result.lead_time / 3600:g} h before TCA, HBR "
            f"{result.hard_body_radius:g} m, {self.method.name}\n"
        )
        print(result.table())
        if result.dilution:
            print(
                "\nnote: the Pc with density uncertainty lies in the dilution region (a smaller "
                "covariance would raise it): a low Pc here says the states are too uncertain to "
                f"tell, not that the objects miss; the largest Pc any covariance gives is "
                f"{float(max(result.pc_max_models)):.4g}"
            )
        if self.json_path is not None:
            summary = {
                "tca": str(message.tca),
                "objects": [message.object1.name, message.object2.name],
                "pc_stated": message.collision_probability,
                "pc_message": result.pc_message,
                "pc_models": dict(zip(result.names, map(float, result.pc_models), strict=True)),
                "weights": dict(zip(result.names, map(float, result.weights), strict=True)),
                "pc_mixture": result.pc,
                "pc_max_message": result.pc_max_message,
                "pc_max_models": dict(
                    zip(result.names, map(float, result.pc_max_models), strict=True)
                ),
                "dilution": result.dilution,
                "lead_time_s": result.lead_time,
                "hard_body_radius_m": result.hard_body_radius,
                "method": self.method.name,
            }
            Path(self.json_path).write_text(json.dumps(summary, indent=2))
            print(f"\nwrote {self.json_path}")
        return result
