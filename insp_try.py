import numpy as np, time, sys
from core import render, RenderSettings, RenderContext
from core.scene.formats import load_scene
from core.paths import SCENES_DIR
from core.inspect import inspect_pixel
scene = load_scene(SCENES_DIR / sys.argv[1])
for shading in sys.argv[2].split(","):
    st = RenderSettings.for_scene(scene, shading=shading, size=(120, 100))
    view = scene.views[0]
    frame = render(scene, view, st, RenderContext())
    ctx = RenderContext()
    rng = np.random.default_rng(1)
    bad = 0; t=time.time(); kinds={}
    for k in range(400):
        x, y = int(rng.integers(120)), int(rng.integers(100))
        r = inspect_pixel(scene, view, st, x, y, ctx)
        kinds[r["layer"]] = kinds.get(r["layer"],0)+1
        d = np.abs(np.array(r["color"]) - frame.color[y, x].astype(int)).max()
        if d > 0:
            bad += 1
            if bad < 3: print("diff", x, y, r["color"], frame.color[y,x], r.get("layer"))
    print(shading, "bad", bad, kinds, "%.1f ms/pixel" % ((time.time()-t)/400*1e3))
