"""Outside references the tests and benches check us against: OpenGL (llvmpipe) and Mitsuba 3."""
