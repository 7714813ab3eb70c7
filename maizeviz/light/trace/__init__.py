"""Rays through a scene: one direction's ground rays and sensor planes (:mod:`.direct`), many
directions for a sky or a period (:mod:`.diffuse`), hit classes (:mod:`.hits`), leaf and soil
optics (:mod:`.optics`), scattering (:mod:`.scatter`) and absorbed light (:mod:`.absorbed`)."""
