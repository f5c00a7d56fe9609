"""The scan-line renderer (``scanline``): Watkins' visible-surface algorithm (FvDFH 15.6) in
the z-buffer's pipeline.

- :mod:`~core.renderers.scanline.draw`: ``draw``, the registered renderer;
- :mod:`~core.renderers.scanline.inspect`: the z-buffer's pixel record with the scan line's
  active edge table and spans, and the buffer views;
- :mod:`~core.renderers.scanline.plan`: the visible-surface stage in place of the z-buffer's.

Nothing is imported here, so that naming a module of the package loads only that module.
"""
