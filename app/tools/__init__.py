"""Command-line tools beside the viewer: bench, report, stability, and the GL oracle they use."""
