"""The systems that bring scene-file keys, imported once so their readers are registered.

The scene reader (``core/scene/formats``) only routes keys to the readers registered in
``core.scene.formats.keys``; each system registers its own when its module is imported.
``core/__init__.py`` imports this module, so a scene file is never read before they are in
place. The order is the order the readers run in, after the scene's own keys: the bump demo's
panel becomes the file's first view before the animation's keys name views.
"""

from core.texture import scenekeys  # noqa: F401  (textures of a material; the demo's panel)
from core.effects import depth_cue  # noqa: F401  ([depth_cue])
from core.animation import keys  # noqa: F401  ([animation], [[key]], [[emitter]])
from core.animation import dynamics_keys  # noqa: F401  ([dynamics], [[body]])
from core.animation import linkage_keys  # noqa: F401  ([[linkage]])
from core.animation import actor_keys  # noqa: F401  ([[actor]])
from core.animation import mocap_keys  # noqa: F401  ([[mocap]])
from core.volume import scenekeys as volume_keys  # noqa: F401  ([[volume]])
from core.shading.models import scenekeys as lighting_keys  # noqa: F401  (a material's model)
