"""The benches: our pipeline's speed against OpenGL, scikit-image and a lean numba floor."""
