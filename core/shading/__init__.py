"""Shading: the Phong illumination model (once) and the shading modes that evaluate it.
"""
