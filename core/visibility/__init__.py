"""Object-precision visible-surface algorithms: the painter's family (the notes' approaches 3
and 4). Each returns an order to paint triangles in, back to front, splitting where no order
exists; the renderers in :mod:`core.renderers.painters` paint that order.

- :mod:`core.visibility.bsp`: the BSP tree (Fuchs, Kedem, Naylor 1980), built once in world
  space, traversed from the eye each frame;
- :mod:`core.visibility.depth_sort`: Newell, Newell and Sancha's depth sort (1972), per frame
  in device space;
- :mod:`core.visibility.split`: cutting a triangle by a plane, shared by both;
- :mod:`core.visibility.watkins`: Watkins' scan-line algorithm (approach 5, FvDFH 15.6): no
  order, but the visible polygon of each span of each scan line, by depth at the span's ends.
"""
