"""What "Measure this scene" says: a preset's accuracy against the exact march,
as lines for the panel, the log and a script. No bpy here."""
from __future__ import annotations

from typing import Mapping

IMAGE_DISAGREEMENT = "Glint Disagreement"
# The keys of glint_core.compare() this add-on reports, in order.
FIGURES = ("precision", "recall", "median_px", "p95_px", "false_reflections")


def summary(result: Mapping) -> str:
    """One line: preset, accuracy, and the two times."""
    return (f"{result['preset']}: precision {result['precision']:.3f}, recall {result['recall']:.3f}, "
            f"pixel error median {result['median_px']:.2f} / p95 {result['p95_px']:.2f} px, "
            f"{result['false_reflections']} false reflections; "
            f"{result['ms']:.0f} ms against exact {result['exact_ms']:.0f} ms "
            f"({result['width']}x{result['height']}, {result['triangles']} triangles, {result['backend']})")


def panel_lines(result: Mapping) -> list:
    """Short lines for the panel's box."""
    return [f"{result['preset']}: P {result['precision']:.3f}  R {result['recall']:.3f}",
            f"error {result['median_px']:.2f} / {result['p95_px']:.2f} px (median / p95)",
            f"{result['ms']:.0f} ms, exact {result['exact_ms']:.0f} ms"]
