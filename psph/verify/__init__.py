"""Analytical references and error norms used by tests, benchmarks and summaries."""

from psph.verify import terzaghi


def reference_times(scene) -> list[float]:
    """Physical times (s) of the scene's verification points."""
    if scene.verification.reference == "terzaghi":
        ref = terzaghi.from_scene(scene)
        return [ref.time_of(tv) for tv in scene.verification.tv]
    return []
