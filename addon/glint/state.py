"""What Glint did last, for the panel and the log. No ``bpy``: plain data only.

Renders run handlers on a worker thread (F12) or the main thread (``-b``);
writing to the scene from there would tag the depsgraph mid-render, so the
results are kept here and the panel reads them.
"""
from __future__ import annotations

import threading
from dataclasses import dataclass, field
from typing import Dict, List, Optional

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
    timings_ms: Dict[str, float] = field(default_factory=dict)


class _State:
    def __init__(self):
        self.lock = threading.Lock()
        self.last: Optional[FrameReport] = None
        self.messages: List[str] = []
        self.cancel = threading.Event()
        self.busy = False
        # The last frame's arrays (position, normal, specular, uv, projection),
        # for the debug operators and for tests that inspect an export.
        self.arrays: Dict[str, object] = {}

    def log(self, message: str) -> str:
        line = f"{PREFIX} {message}"
        print(line, flush=True)
        with self.lock:
            self.messages.append(message)
            del self.messages[:-20]
        return line


STATE = _State()


def log(message: str) -> str:
    return STATE.log(message)
