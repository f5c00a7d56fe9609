"""The desktop side: glfw window, Dear ImGui menu, input, the blit, and the command line.

Thin by design: geometry, clipping, depth and shading all live in ``core``; ``app`` only asks
the core for a frame and shows it.
"""
