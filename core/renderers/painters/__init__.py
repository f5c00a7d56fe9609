"""The painter's renderers (``bsp``, ``depth-sort``): an order found, painted back to front.

- :mod:`~core.renderers.painters.draw`: ``draw_bsp`` and ``draw_depth_sort``, the registered
  renderers;
- :mod:`~core.renderers.painters.inspect`: the pixel's history and the overdraw buffer;
- :mod:`~core.renderers.painters.plan`: the ordering stage each adds to the plan.

Nothing is imported here, so that naming a module of the package loads only that module.
"""
