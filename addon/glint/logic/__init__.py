"""Glint's pure logic: no ``import bpy`` and no ``import glint_core`` anywhere in
this package, so that plain pytest (``tests/addon``) can check every rule the
add-on applies without Blender or the native module."""
