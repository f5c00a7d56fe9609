"""The effects drawn over a renderer's picture: depth cueing and transparency (FvDFH 16.1.3, 16.5).

They are the light-source-independent models of the course's lecture on them, applied to what
any renderer drew: :mod:`core.effects.depth_cue` blends each pixel toward the cue colour by its
depth (the tracers' depth comes from their primary rays), :mod:`core.effects.transparency`
composites the surfaces with ``k_t > 0`` over the opaque picture by the painter's order. They
sit above the renderers' packages they read (``raytrace``, ``visibility``) and below
``core.render``, which applies them.
"""
