"""Colour science: the CIE 1931 standard observer, chromaticity, the sRGB colour space and
its transfer curve, and the chromaticity diagram (the course's "Color Theory / Perception").

- :mod:`core.colour.cie`: the 2° colour-matching functions (``cie1931_2deg_5nm.csv``, CIE
  015:2004), XYZ → xy, the spectral locus;
- :mod:`core.colour.srgb`: the sRGB primaries and D65 white (IEC 61966-2-1), the RGB → XYZ
  matrix they make, the encoding curve;
- :mod:`core.colour.diagram`: the xy diagram drawn with numpy onto an image;
- :mod:`core.colour.perception`: CIE L*, and the perception chart (simultaneous contrast;
  even steps of code beside even steps of light).
"""
