"""What functional-structural plant models (OpenAlea's ADEL, CN-Wheat, ...) call: a light model
with Caribu's interface (:class:`~maizeviz.fspm.caribu.CaribuScene`), backed by maizeviz's
Embree tracer."""

from maizeviz.fspm.caribu import CaribuScene, CaribuSceneError

__all__ = ["CaribuScene", "CaribuSceneError"]
