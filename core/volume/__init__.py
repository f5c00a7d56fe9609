"""Volume visualization (FvDFH 20.6, the syllabus's "Volume Visualization (Surface and Volume
Rendering)"): sampled 3D data, its isosurface as an ordinary mesh, and direct rendering.

- :mod:`core.volume.data`: :class:`Volume` (samples, spacing, transform, how it is drawn), the
  memory budget and the checks every reader and generator passes its samples through;
- :mod:`core.volume.generators`: the 3D Shepp–Logan phantom, a sphere, metaballs, a torus's
  signed distance;
- :mod:`core.volume.readers`: raw bytes (dims, spacing, dtype, byte order), NRRD (pynrrd),
  NIfTI (nibabel), DICOM series (pydicom);
- :mod:`core.volume.marching`: marching cubes (Lorensen–Cline) with the asymptotic decider on
  ambiguous faces and the body saddle for a cell's two loops: a closed, consistently wound
  mesh with gradient normals;
- :mod:`core.volume.raymarch`: the ray marcher's kernels (trilinear samples, emission–absorption
  front to back with early termination, gradient shading by the Phong model, MIP);
- :mod:`core.volume.scenekeys`: the scene file's ``[[volume]]`` tables.

The renderer that draws with them (``--renderer volume``: opaque geometry by the z-buffer,
then the volumes' rays cut at its depth; its pixel record: the ray, each volume's samples, the
marching cube an isosurface point lies in) is :mod:`core.renderers.volume`.
"""
