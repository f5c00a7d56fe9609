"""Renderers behind :func:`core.render.render`: the z-buffer pipeline and the analytic ray caster.
"""
