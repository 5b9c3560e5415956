"""Blender without a window (the bpy module, or blender --background): the
extension zip installed and enabled as Edit > Preferences > Get Extensions >
Install from Disk does. For the tests and the benchmark, run in Blender's
Python; set BLENDER_USER_RESOURCES to a temporary folder first, so that the
user's own Blender folder is left alone."""

from __future__ import annotations

import os

import bpy

MODULE = "bl_ext.user_default.sorpia_blender"


def install(zip_path: str) -> str:
    """Install and enable the extension zip in the user repository; returns the add-on's module name."""
    (repo,) = [r for r in bpy.context.preferences.extensions.repos if r.module == "user_default"]
    # Without the repository's folder Blender installs the files but fails to load the add-on ("No module named
    # bl_ext.user_default...").
    os.makedirs(repo.directory, exist_ok=True)
    bpy.ops.extensions.package_install_files(filepath=str(zip_path), repo="user_default", enable_on_install=True)
    if MODULE not in bpy.context.preferences.addons:
        raise RuntimeError(f"{zip_path}: installed, but {MODULE} is not enabled")
    return MODULE
