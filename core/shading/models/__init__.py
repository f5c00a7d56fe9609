"""Lighting models (BRDFs): the registered ones. A model is one module and one line here.

A material chooses its model with the scene file's ``model`` key (default ``"phong"``, the
course's model, FvDFH 16.1–16.2); the kernels reach it through
:mod:`core.shading.models.dispatch`, generated from these registrations (so compiled kernels
depend on this file: core.jit's stamp covers it; kernels are generated from this file).
:mod:`core.shading.models.registry` says what a model module defines.
"""

from core.shading.models.registry import (DEFAULT_MODEL, LightingModel, Parameter,  # noqa: F401
                                          lighting_model, lighting_model_names,
                                          lighting_models, model_id, model_of, pack_model,
                                          register_lighting_model, scene_lit_by,
                                          unregister_lighting_model, with_model)

register_lighting_model("phong", "core.shading.models.phong", label="Phong (FvDFH 16.2)",
                        description="ambient + Lambert diffuse + (R·V)^n or (N·H)^n specular")
register_lighting_model("cook-torrance", "core.shading.models.cook_torrance",
                        label="Cook–Torrance (FvDFH 16.7)",
                        description="microfacets: Beckmann's D, the V-cavity G, Schlick's F",
                        parameters=(Parameter("roughness", 0.3, 0.01, 1.0,
                                              help="Beckmann's rms slope of the facets, m"),
                                    Parameter("f0", (0.04, 0.04, 0.04), 0.0, 1.0, size=3,
                                              help="reflectance at normal incidence (Schlick)")))
