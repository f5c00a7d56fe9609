"""The volume bench's peer rows: VTK's ``vtkFixedPointVolumeRayCastMapper`` (a CPU ray caster)
and ``vtkFlyingEdges3D`` on the same phantom, view, transfer function and size as ours.

VTK is not a dependency (it is the ``bench`` extra: ``pip install -e .[bench]``); without it
:func:`available` is False and the bench says so in one line. The window is VTK's offscreen
one (EGL or OSMesa, Mesa's llvmpipe here); OpenGL only shows the mapper's finished picture.

How ours maps onto VTK's terms:

- the volume: ``values[i, j, k]`` with i along x is VTK's x-fastest order, origin and spacing
  as :meth:`core.volume.data.Volume.world_from_index` places it (the default transform);
- the view: the camera at ``vrp + |prp_n| · vpn`` (``prp`` on the view-plane normal) looking at
  ``vrp``, ``vup`` up, the window's height over ``prp_n`` as the view angle;
- the transfer function: colours piecewise linear at its points; VTK's opacity is per
  ``ScalarOpacityUnitDistance`` of world length, so σ becomes ``α = 1 − e^{−σ u}`` with ``u``
  the sample step (exact at that step), sampled finely because it is not linear in σ;
- the step: ours (half the smallest voxel side), with VTK's automatic coarsening off;
- gradient shading: VTK's own (its headlight-less Phong, the light as a direction), so that
  picture differs from ours by design; unlit and MIP are the same integral.
"""

from __future__ import annotations

import numpy as np

FINE = 1024                   # points of the opacity curve handed to VTK


def available() -> bool:
    try:
        import vtkmodules.vtkRenderingVolume  # noqa: F401
    except ImportError:
        return False
    return True


def version() -> str:
    from vtkmodules.vtkCommonCore import vtkVersion
    return vtkVersion.GetVTKVersion()


def image_data(values, spacing):
    """``values`` (nx, ny, nz) as vtkImageData, centred on the origin as ours is."""
    from vtkmodules.util.numpy_support import numpy_to_vtk
    from vtkmodules.vtkCommonDataModel import vtkImageData
    image = vtkImageData()
    image.SetDimensions(*values.shape)
    image.SetSpacing(*spacing)
    image.SetOrigin(*(-np.asarray(spacing) * (np.asarray(values.shape) - 1) / 2.0))
    flat = np.ascontiguousarray(values.transpose(2, 1, 0)).reshape(-1)   # x fastest
    array = numpy_to_vtk(flat, deep=True)
    array.SetName("values")
    image.GetPointData().SetScalars(array)
    return image


def volume_property(transfer, mode, lighting, step, value_range, light_model):
    from vtkmodules.vtkCommonDataModel import vtkPiecewiseFunction
    from vtkmodules.vtkRenderingCore import vtkColorTransferFunction, vtkVolumeProperty
    colour, opacity = vtkColorTransferFunction(), vtkPiecewiseFunction()
    prop = vtkVolumeProperty()
    if mode == "mip":                              # grey over the data's range, opaque
        lo, hi = value_range
        colour.AddRGBPoint(lo, 0, 0, 0)
        colour.AddRGBPoint(hi, 1, 1, 1)
        opacity.AddPoint(lo, 1.0)
        opacity.AddPoint(hi, 1.0)
    else:
        for value, r, g, b, _ in transfer:
            colour.AddRGBPoint(value, r, g, b)
        lo, hi = min(transfer[0, 0], value_range[0]), max(transfer[-1, 0], value_range[1])
        for value in np.linspace(lo, hi, FINE):
            sigma = np.interp(value, transfer[:, 0], transfer[:, 4])
            opacity.AddPoint(value, 1.0 - np.exp(-sigma * step))
        prop.SetScalarOpacityUnitDistance(step)
    prop.SetColor(colour)
    prop.SetScalarOpacity(opacity)
    prop.SetInterpolationTypeToLinear()
    if lighting == "gradient" and mode != "mip":
        prop.ShadeOn()
        ambient, diffuse, specular, exponent = light_model
        prop.SetAmbient(ambient)
        prop.SetDiffuse(diffuse)
        prop.SetSpecular(specular)
        prop.SetSpecularPower(exponent)
    return prop


class VtkVolume:
    """One offscreen window drawing the phantom by the fixed-point ray caster."""

    def __init__(self, values, spacing, view, size, transfer, mode, lighting, step,
                 light_position, light_model):
        from vtkmodules.vtkRenderingCore import (vtkLight, vtkRenderer, vtkRenderWindow,
                                                 vtkVolume)
        from vtkmodules.vtkRenderingVolume import vtkFixedPointVolumeRayCastMapper
        import vtkmodules.vtkRenderingOpenGL2  # noqa: F401  (the window's factory)
        import vtkmodules.vtkRenderingVolumeOpenGL2  # noqa: F401  (the picture's display)
        mapper = vtkFixedPointVolumeRayCastMapper()
        mapper.SetInputData(image_data(values, spacing))
        mapper.SetAutoAdjustSampleDistances(0)
        mapper.SetLockSampleDistanceToInputSpacing(0)
        mapper.SetSampleDistance(step)
        mapper.SetImageSampleDistance(1.0)
        if mode == "mip":
            mapper.SetBlendModeToMaximumIntensity()
        else:
            mapper.SetBlendModeToComposite()
        volume = vtkVolume()
        volume.SetMapper(mapper)
        volume.SetProperty(volume_property(transfer, mode, lighting, step,
                                           (float(values.min()), float(values.max())),
                                           light_model))
        self.renderer = vtkRenderer()
        self.renderer.SetBackground(0, 0, 0)
        self.renderer.AddVolume(volume)
        self.renderer.AutomaticLightCreationOff()
        light = vtkLight()
        light.SetPosition(*light_position)
        light.SetFocalPoint(0, 0, 0)
        self.renderer.AddLight(light)
        self.window = vtkRenderWindow()
        self.window.SetOffScreenRendering(1)
        self.window.SetSize(*size)
        self.window.AddRenderer(self.renderer)
        self._camera(view)

    def _camera(self, view):
        camera = self.renderer.GetActiveCamera()
        vrp, vpn = np.asarray(view.vrp, float), np.asarray(view.vpn, float)
        distance = float(view.prp[2])
        camera.SetFocalPoint(*vrp)
        camera.SetPosition(*(vrp + distance * vpn / np.linalg.norm(vpn)))
        camera.SetViewUp(*view.vup)
        half = (view.window[3] - view.window[2]) / 2.0
        camera.SetViewAngle(float(np.degrees(2.0 * np.arctan(half / distance))))
        camera.SetClippingRange(distance - view.front, distance - view.back)

    def render(self) -> None:
        self.window.Render()

    def picture(self) -> np.ndarray:
        """(H, W, 3) uint8, top row first (ours)."""
        from vtkmodules.util.numpy_support import vtk_to_numpy
        from vtkmodules.vtkRenderingCore import vtkWindowToImageFilter
        grab = vtkWindowToImageFilter()
        grab.SetInput(self.window)
        grab.SetInputBufferTypeToRGB()
        grab.ReadFrontBufferOff()
        grab.Update()
        width, height = self.window.GetSize()
        pixels = vtk_to_numpy(grab.GetOutput().GetPointData().GetScalars())
        return pixels.reshape(height, width, -1)[::-1, :, :3].copy()


def flying_edges(values, spacing, iso):
    """A callable extracting the iso-surface by ``vtkFlyingEdges3D`` (VTK's threads: all
    cores) and the triangle count it gives."""
    from vtkmodules.vtkFiltersCore import vtkFlyingEdges3D
    image = image_data(values, spacing)

    def extract():
        edges = vtkFlyingEdges3D()
        edges.SetInputData(image)
        edges.SetValue(0, iso)
        edges.ComputeNormalsOn()
        edges.ComputeGradientsOff()
        edges.ComputeScalarsOff()
        edges.Update()
        return edges.GetOutput()

    return extract, extract().GetNumberOfPolys()
