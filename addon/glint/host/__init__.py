"""Everything that differs between the Blenders Glint runs on, in one place.

* :mod:`.engines`: engine ids, Eevee Legacy or Next, Eevee's own reflections;
* :mod:`.nodes`: where the compositor tree lives, which node types and
  options it has, how sockets are addressed, the Render Layers' pass names,
  the File Output node;
* :mod:`.writes`: main-thread writes where Blender has left Python's
  writes refused (one flag for all threads up to 4.x, per thread in 5.x);
* this module: which Blenders were tested, and what the running one is.

Each difference is chosen by a feature test of the running Blender. The
version number is read to say, once, that a Blender was not tested, and in
two places where no feature of the API tells two Blenders apart: which
releases a measured behaviour was measured on (nodes.scale_offset_places_read,
draws_during_export below). Nothing outside this package knows a Blender
version.
"""
from __future__ import annotations

from typing import Optional, Tuple

import bpy

# The Blenders the test suite runs on (scripts/hosts/hosts.conf, README's table).
TESTED = ((3, 4), (4, 3), (5, 2))


def version() -> Tuple[int, int, int]:
    return tuple(bpy.app.version)


def version_text() -> str:
    return bpy.app.version_string


def untested_note() -> Optional[str]:
    """A sentence for the log when this Blender is not one the tests run on."""
    if tuple(bpy.app.version[:2]) in TESTED:
        return None
    tested = ", ".join(f"{a}.{b}" for a, b in TESTED)
    return (f"Blender {bpy.app.version_string} is not one Glint is tested on ({tested}); "
            "it should work, and a frame it cannot handle renders without reflections")


def draws_during_export() -> bool:
    """Whether Blender's window is redrawn while a handler of the render's
    depsgraph (``frame_change_post``, where Glint's export runs) is busy.
    Measured under Xvfb with draw handlers counting (docs/addon.md,
    Limitations): 3.4 and 4.3 draw, 5.2 does not, although its timers run. No
    API tells: by version."""
    return tuple(bpy.app.version[:2]) < (5, 0)
