"""Scenes: TOML → frozen records in SI, validated before any work, and the resolved scene back to
TOML.

Every key may be written in SI (``crank_radius = 0.047``) or with one unit suffix at the edge
(``crank_radius_mm = 47``). Unknown keys, wrong types and non-physical values raise
:class:`transient.errors.SceneError` naming the file, the key, what is wrong and what is allowed.

- :mod:`.reader`   :class:`~transient.scene.reader.Section`, the typed-key reader of one table
                   (unit suffixes, ranges, unknown keys)
- :mod:`.records`  the frozen dataclasses, one per table, with their units
- :mod:`.read`     :func:`~transient.load_scene` and :func:`~.read.scene_from_dict`: the reader
                   of each table
- :mod:`.checks`   the checks across tables
- :mod:`.write`    :func:`~.write.to_toml`, the resolved scene back to TOML
"""
from .read import load_scene, replace_scene, scene_from_dict
from .records import (
                      POLICIES,
                      Analysis,
                      Cylinder,
                      Friction,
                      Gas,
                      Governor,
                      Inertia,
                      Initial,
                      Load,
                      LoadTable,
                      Output,
                      Pair,
                      Run,
                      Scene,
                      Solver,
                      Starter,
                      Wiebe,
                      Woschni,
                      runs_compiled,
)
from .write import to_toml

# Scenes from code: the records cannot import their reader (it imports them), so the methods
# that build, change and write a scene are bound to the class here, where both are known.
Scene.from_dict = staticmethod(scene_from_dict)
Scene.replace = replace_scene
Scene.to_toml = to_toml

__all__ = ["load_scene", "scene_from_dict", "replace_scene", "to_toml", "Scene", "Inertia", "Gas", "Wiebe",
           "Woschni", "Cylinder", "Load", "LoadTable", "Starter", "Governor", "Initial", "Run",
           "Solver", "Output", "Friction", "Pair", "Analysis", "POLICIES", "runs_compiled"]
