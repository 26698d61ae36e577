"""The figures of a scene: which of the stages' declared figures a scene gets, as ``plot`` draws
them into PNG files and ``report`` into its page (the one place that chooses them)."""

from __future__ import annotations

from . import engine
from .stage import stages


def scene_figures(sc) -> tuple[list, list]:
    """The figures ``plot`` draws for a scene, and those it skips because the scene does not ask
    for an optional output they need."""
    needed = {st.name for st in engine.needed_stages(sc, sc.outputs)}
    figures = [f for st in stages().values() for f in st.figures if set(f.stages) <= needed]
    asked = set(sc.outputs)
    return [f for f in figures if set(f.outputs) <= asked], [f for f in figures if not set(f.outputs) <= asked]


def use_agg():
    """matplotlib on its file-only backend (no display needed); returns pyplot."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


__all__ = ["scene_figures", "use_agg"]
