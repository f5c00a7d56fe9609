"""The camera: an FvDFH view (VRP, VPN, VUP, window, PRP, F, B) and what follows from it.

- :mod:`core.camera.view` — the VRC basis and the normalizing transforms N_per and N_par;
"""

from core.camera.view import View, ViewError

__all__ = ["View", "ViewError"]
