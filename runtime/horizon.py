"""The scene a command names (--scene) and the horizon of its run (--t-end, else the scene's usual one)."""
from __future__ import annotations

import sys

from codegen.scene import SceneError, load_scene

DEFAULT_T_END = {"paper_case1": 1.5, "paper_case2": 1.75}     # s; any other scene: 1.0


def scene_and_horizon(args):
    """The scene named by ``args.scene`` and the run's horizon (``args.t_end``, else the scene's usual one),
    or None after printing why the scene cannot be loaded.  The scene's warnings are printed on loading."""
    try:
        scene = load_scene(args.scene)
    except SceneError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return None
    for warning in scene.warnings:                # values that suggest a slip of units: said, not refused
        print(f"warning: {warning}", file=sys.stderr)
    return scene, (args.t_end if args.t_end is not None else DEFAULT_T_END.get(scene.name, 1.0))
