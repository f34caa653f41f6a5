"""What Glint did last, for the panel and the log. No ``bpy``: plain data only.

Renders run handlers on a worker thread (F12) or the main thread (``-b``);
writing to the scene from there would tag the depsgraph mid-render, so the
results are kept here and the panel reads them. What must happen on Blender's
main thread (a report, repairing the compositor set-up) is queued with
:meth:`_State.after_render`, which also waits for the render job to end;
``handlers`` runs the queue from a timer, which also redraws the panel.
"""
from __future__ import annotations

import queue
import threading
from dataclasses import dataclass, field
from typing import Callable, Dict, List, Optional, Tuple

PREFIX = "Glint:"


@dataclass
class FrameReport:
    frame: int = 0
    status: str = ""  # "ok", "skipped", "error", "cancelled"
    message: str = ""
    backend: str = ""
    width: int = 0
    height: int = 0
    triangles: int = 0
    objects: int = 0
    culled: int = 0
    reflective_pixels: int = 0
    # (x0, y0, x1, y1): the pixels the compositor's group works on, the rest of
    # the frame passes through (logic/group_images.image_region)
    region: Tuple[int, int, int, int] = (0, 0, 0, 0)
    timings_ms: Dict[str, float] = field(default_factory=dict)


class _State:
    def __init__(self):
        self.lock = threading.Lock()
        self.last: Optional[FrameReport] = None
        self.messages: List[str] = []
        self.cancel = threading.Event()
        self.busy = False  # a frame's export and trace are running
        # A render with Glint on is under way (render_init to its end): the
        # panel offers Cancel Glint from then on, not only while busy, since
        # Blender 5.x draws nothing while the export runs (handlers.on_render_pre).
        self.rendering = False
        # Set when the panel has drawn during that render; panel_drawn_at, when
        # it last drew at all (time.monotonic()): whether it is on screen.
        self.panel_drawn = threading.Event()
        self.panel_drawn_at = float("-inf")
        # "export 40% (...)" while a render's export reports progress, else "".
        self.progress = ""
        # Bumped on every change the panel shows: the main thread redraws on a change.
        self.version = 0
        self.after_render_queue: "queue.SimpleQueue[Callable[[], None]]" = queue.SimpleQueue()
        # The last frame's arrays (position, normal, specular, uv, projection),
        # for the debug operators and for tests that inspect an export.
        self.arrays: Dict[str, object] = {}
        # The last "Measure this scene" figures (logic/measurement.py), for the panel.
        self.measurement: Dict[str, object] = {}
        # Where the last render's engine specular S came from (logic/world.py:
        # "world colour" or "Eevee passes"), None for other engines.
        self.specular_source: Optional[str] = None
        # Whether the group runs the second bounce, as compositor.ensure set it
        # (None before it ran): the frame's log line reads it here, not from the
        # node tree, which the render thread had better not walk.
        self.second_bounce: Optional[bool] = None
        # Blender refused Python's writes where nothing read-only was running
        # (host/writes.py): its read-only flag is stuck until it restarts.
        self.writes_stuck = False

    def log(self, message: str) -> str:
        line = f"{PREFIX} {message}"
        print(line, flush=True)
        with self.lock:
            self.messages.append(message)
            del self.messages[:-20]
        self.touch()
        return line

    def touch(self) -> None:
        """Something the panel shows changed."""
        with self.lock:
            self.version += 1

    def after_render(self, fn: Callable[[], None]) -> None:
        """Run ``fn`` on Blender's main thread once no render job is running
        (from any thread): for work that calls operators under a context
        override or edits the node tree the render composites with."""
        self.after_render_queue.put(fn)


STATE = _State()


def log(message: str) -> str:
    return STATE.log(message)
