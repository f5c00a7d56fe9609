"""Volume visualization (FvDFH 20.6, the syllabus's "Volume Visualization (Surface and Volume
Rendering)"): sampled 3D data, its isosurface as an ordinary mesh, and direct rendering.

- :mod:`core.volume.data`: :class:`Volume` (samples, spacing, transform, how it is drawn), the
  memory budget and the checks every reader and generator passes its samples through;
- :mod:`core.volume.generators`: the 3D Shepp–Logan phantom, a sphere, metaballs, a torus's
  signed distance;
- :mod:`core.volume.readers`: raw bytes (dims, spacing, dtype, byte order), NRRD (pynrrd),
  NIfTI (nibabel);
- :mod:`core.volume.marching`: marching cubes (Lorensen–Cline) with the asymptotic decider on
  ambiguous faces: a closed, consistently wound mesh with gradient normals;
- :mod:`core.volume.raymarch`: the ray marcher's kernels (trilinear samples, emission–absorption
  front to back with early termination, gradient shading by the Phong model, MIP);
- :mod:`core.volume.renderer`: ``--renderer volume``: opaque geometry by the z-buffer, then the
  volumes' rays cut at its depth;
- :mod:`core.volume.scenekeys`: the scene file's ``[[volume]]`` tables.
"""
