"""The two-pass method: the course's hybrid of the local and global models (radiosity for the
diffuse part, ray tracing for the specular part; Wallace, Cohen and Greenberg 1987; Sillion and
Puech 1989).

- pass 1, view-independent: the radiosity solution (:mod:`core.radiosity`, unchanged, kept with
  the scene in the render context as the radiosity renderer keeps it);
- pass 2, view-dependent (:mod:`~core.twopass.second_pass`): an eye ray per pixel sample; at
  each hit the diffuse term is the solution's radiosity there, interpolated from the vertex
  values as the radiosity renderer displays it, plus the specular part as Whitted traces it
  (the k_s highlight of the point and directional lights, k_r I_r, k_t I_t), the reflected and
  refracted rays shaded the same way at their own hits.

Here: ``second_pass`` (the rays, in waves through the ray tracer's BVH kernels). The
registered ``"twopass"`` renderer, its stages in the plan and its pixel inspector are
:mod:`core.renderers.twopass`. Nothing is imported here, so that naming a module of the
package loads only that module.
"""
