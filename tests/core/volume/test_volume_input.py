"""Bad volume input: one clear message each (what, where, the line), and nothing allocated
beyond the budget a header's numbers are checked against (core.volume.data.MAX_VOXELS)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from core.render import render
from core.scene.formats import ReaderError
from core.settings import RenderSettings
from core.scene.formats.scenefile import read_scene_file
from core.volume.data import MAX_VOXELS, volumes_of
from tests.tools import need_module

nibabel = need_module("nibabel", "NIfTI files are read through nibabel")
nrrd = need_module("nrrd", "NRRD files are read through pynrrd")

HEAD = """
[[geometry]]
generator = "cube"
params = { size = 0.1 }

[[volume]]
"""


def load(tmp_path: Path, volume: str):
    text = HEAD + volume
    (tmp_path / "scene.toml").write_text(text)
    return read_scene_file(text, str(tmp_path / "scene.toml"), tmp_path)


def refused(tmp_path, volume: str) -> str:
    with pytest.raises(ReaderError) as error:
        load(tmp_path, volume)
    return str(error.value)


def test_a_good_raw_file_is_read_x_fastest(tmp_path):
    data = np.arange(4 * 3 * 2, dtype="<u2")          # x fastest, then y, then z
    data.tofile(tmp_path / "v.raw")
    scene = load(tmp_path, 'file = "v.raw"\nraw = { dims = [4, 3, 2], dtype = "uint16" }\n'
                           'mode = "mip"\nspacing = [1, 2, 3]')
    (volume,) = volumes_of(scene)
    assert volume.dims == (4, 3, 2) and volume.spacing == (1.0, 2.0, 3.0)
    assert volume.values[1, 2, 1] == 1 + 4 * 2 + 12 * 1


def test_big_endian_raw(tmp_path):
    np.arange(8, dtype=">i2").tofile(tmp_path / "v.raw")
    scene = load(tmp_path, 'file = "v.raw"\nmode = "mip"\n'
                           'raw = { dims = [2, 2, 2], dtype = "int16", byte_order = "big" }')
    assert volumes_of(scene)[0].values[1, 1, 1] == 7


def test_dims_that_disagree_with_the_file_size(tmp_path):
    np.zeros(30, np.uint8).tofile(tmp_path / "v.raw")
    message = refused(tmp_path, 'file = "v.raw"\nmode = "mip"\nraw = { dims = [2, 2, 2] }')
    assert message.endswith("scene.toml:7: volume[1].file: v.raw: the file is longer than its "
                            "dims say: it has 30 bytes, and dims 2 x 2 x 2 of uint8 after 0 "
                            "header bytes need 8")


def test_a_truncated_raw_file(tmp_path):
    np.zeros(7, np.float32).tofile(tmp_path / "v.raw")
    message = refused(tmp_path, 'file = "v.raw"\nmode = "mip"\n'
                                'raw = { dims = [2, 2, 2], dtype = "float32" }')
    assert "v.raw: the file is truncated: it has 28 bytes" in message
    assert "need 32" in message


def test_a_2_to_the_40_voxel_header_is_refused_from_its_numbers(tmp_path):
    (tmp_path / "v.raw").write_bytes(b"\0" * 16)
    message = refused(tmp_path, 'file = "v.raw"\nmode = "mip"\n'
                                'raw = { dims = [1048576, 1024, 1024] }')
    assert (f"1048576 x 1024 x 1024 = {2 ** 40} voxels (2^40.0) is over the budget of "
            f"{MAX_VOXELS}" in message)
    # the same in an NRRD header (the data is never read)
    (tmp_path / "big.nrrd").write_bytes(b"NRRD0004\ntype: uint8\ndimension: 3\n"
                                        b"sizes: 1048576 1024 1024\nencoding: raw\n\n\0\0")
    message = refused(tmp_path, 'file = "big.nrrd"\nmode = "mip"')
    assert "big.nrrd: 1048576 x 1024 x 1024" in message and "over the budget" in message


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_nan_and_infinite_samples(tmp_path, bad):
    data = np.zeros((2, 3, 4), np.float32)              # stored z, y, x: (x, y, z) = (3, 2, 1)
    data[1, 2, 3] = bad
    data.tofile(tmp_path / "v.raw")
    message = refused(tmp_path, 'file = "v.raw"\nmode = "mip"\n'
                                'raw = { dims = [4, 3, 2], dtype = "float32" }')
    assert message.endswith("volume[1].file: v.raw: 1 samples are NaN or infinite (or beyond "
                            "float32), the first at voxel (i, j, k) = (3, 2, 1)")


def test_an_empty_transfer_function(tmp_path):
    message = refused(tmp_path, 'generator = "sphere"\nparams = { size = 8 }\ntransfer = []')
    assert message.endswith("volume[1].transfer: the transfer function is empty; it needs at "
                            "least one [value, r, g, b, alpha] point")


def test_emission_absorption_without_a_transfer_function(tmp_path):
    message = refused(tmp_path, 'generator = "sphere"\nparams = { size = 8 }')
    assert "volume[1]: emission-absorption needs a 'transfer' function" in message


def test_an_iso_value_outside_the_data(tmp_path):
    message = refused(tmp_path, 'generator = "sphere"\nparams = { size = 8, density = 2.0 }\n'
                                'mode = "isosurface"\niso = 3.5')
    assert message.endswith("volume[1].iso: iso 3.5 is outside the data's range (0, 2): no "
                            "surface")


@pytest.mark.parametrize("spacing", ["[0, 1, 1]", "[1, -0.5, 1]"])
def test_spacing_of_zero_or_below(tmp_path, spacing):
    message = refused(tmp_path, f'generator = "sphere"\nparams = {{ size = 8 }}\n'
                                f'mode = "mip"\nspacing = {spacing}')
    assert "volume[1].spacing: spacing must be three finite numbers > 0" in message


def test_a_truncated_nifti(tmp_path):
    image = nibabel.Nifti1Image(np.ones((8, 8, 8), np.float32), np.eye(4))
    nibabel.save(image, str(tmp_path / "v.nii"))
    whole = (tmp_path / "v.nii").read_bytes()
    (tmp_path / "v.nii").write_bytes(whole[:-100])
    message = refused(tmp_path, 'file = "v.nii"\nmode = "mip"')
    assert f"v.nii: the file is truncated: it has {len(whole) - 100} bytes" in message
    assert "8 x 8 x 8 needs" in message


def test_a_truncated_gzipped_nifti(tmp_path):
    image = nibabel.Nifti1Image(np.random.default_rng(0).random((8, 8, 8), np.float32),
                                np.eye(4))
    nibabel.save(image, str(tmp_path / "v.nii.gz"))
    whole = (tmp_path / "v.nii.gz").read_bytes()
    (tmp_path / "v.nii.gz").write_bytes(whole[: len(whole) // 2])
    message = refused(tmp_path, 'file = "v.nii.gz"\nmode = "mip"')
    assert "v.nii.gz: not a readable NIfTI file (truncated or malformed" in message


def test_a_truncated_nrrd(tmp_path):
    nrrd.write(str(tmp_path / "v.nrrd"), np.ones((6, 6, 6), np.int16),
               {"encoding": "raw", "spacings": [0.5, 0.5, 1.0]})
    good = load(tmp_path, 'file = "v.nrrd"\nmode = "mip"')
    assert volumes_of(good)[0].spacing == (0.5, 0.5, 1.0)
    whole = (tmp_path / "v.nrrd").read_bytes()
    (tmp_path / "v.nrrd").write_bytes(whole[:-50])
    message = refused(tmp_path, 'file = "v.nrrd"\nmode = "mip"')
    assert f"v.nrrd: the file is truncated: it has {len(whole) - 50} bytes" in message


def test_nibabels_own_mr_volume():
    """Real data: the anatomical MR volume nibabel's wheel ships for its own tests."""
    source = Path(nibabel.__file__).parent / "tests" / "data" / "anatomical.nii"
    if not source.exists():
        pytest.skip("this nibabel wheel ships no anatomical.nii")
    from core.volume.readers import read_nifti
    values, spacing = read_nifti(source)
    image = nibabel.load(str(source))
    assert values.shape == tuple(image.shape[:3])
    assert spacing == pytest.approx(image.header.get_zooms()[:3])
    assert np.array_equal(values, np.asarray(image.dataobj, dtype=np.float32).reshape(
        values.shape))
    assert math.isfinite(float(values.max())) and values.max() > values.min()


def ct_series(folder: Path, count: int = 5, gap: float = 5.0) -> list[Path]:
    """``count`` slices made from pydicom's own CT slice, ``gap`` mm apart along z, each
    slice's pixels offset by its number (so the order can be checked)."""
    pydicom = need_module("pydicom", "DICOM series are read through pydicom")
    from pydicom.data import get_testdata_file
    source = get_testdata_file("CT_small.dcm")
    folder.mkdir()
    paths = []
    for k in range(count):
        ds = pydicom.dcmread(source)
        x, y, z = (float(c) for c in ds.ImagePositionPatient)
        ds.ImagePositionPatient = [x, y, z + gap * k]
        ds.PixelData = (ds.pixel_array + np.int16(10 * k)).astype(np.int16).tobytes()
        path = folder / f"slice{(count - k) % count:02d}.dcm"      # file names out of order
        ds.save_as(path)
        paths.append(path)
    return paths


def test_a_dicom_series_in_slice_order(tmp_path):
    pydicom = need_module("pydicom", "DICOM series are read through pydicom")
    paths = ct_series(tmp_path / "ct")
    scene = load(tmp_path, 'file = "ct"\nmode = "mip"')
    (volume,) = volumes_of(scene)
    assert volume.dims == (128, 128, 5)
    assert volume.spacing == pytest.approx((0.661468, 0.661468, 5.0))
    first = pydicom.dcmread(paths[0])
    hounsfield = first.pixel_array.astype(np.float64) * float(first.RescaleSlope) \
        + float(first.RescaleIntercept)
    assert np.array_equal(volume.values[:, :, 0], hounsfield.T.astype(np.float32))
    assert np.array_equal(volume.values[:, :, 3] - volume.values[:, :, 0],
                          np.full((128, 128), 30.0, np.float32))


def test_a_dicom_series_with_a_missing_slice(tmp_path):
    paths = ct_series(tmp_path / "ct")
    paths[2].unlink()
    message = refused(tmp_path, 'file = "ct"\nmode = "mip"')
    assert message.endswith("volume[1].file: ct: a slice is missing between slice04.dcm "
                            "(-70.7 mm) and slice02.dcm (-60.7 mm): a gap of 10 mm where the "
                            "slices are 5 mm apart")


def test_a_generator_beyond_the_budget(tmp_path):
    message = refused(tmp_path, 'generator = "sphere"\nparams = { size = 500 }\nmode = "mip"')
    assert message.endswith("volume[1].params: sphere: size must be a whole number of samples "
                            "from 2 to 406, not 500")


VALUES = ["0", "-1", "1e308", "nan", "inf", "-inf", '"x"', "[]", "[1, 2]", "[0, 0, 0]",
          "[[1, 2, 3, 4, 5]]", "true", "{}", "9223372036854775807", "2.5", '"mip"',
          '"isosurface"', '"shepp-logan"', "[2, 2, 2]", "[[0, 0, 0, 0, 0], [0, 1, 1, 1, 1]]"]
GOOD = {"generator": '"sphere"', "params": "{ size = 6, radius = 0.5 }",
        "mode": '"emission-absorption"', "iso": "0.5", "spacing": "[0.5, 0.5, 0.5]",
        "transfer": "[[0.0, 0, 0, 0, 0], [1.0, 1, 1, 1, 2]]", "lighting": '"gradient"',
        "window": "[0, 1]", "transform": "{ scale = 2 }", "material": "{ ka = 0.5 }",
        "name": '"v"'}


@pytest.mark.parametrize("seed", range(3))
def test_mutated_volume_tables_are_read_or_refused_never_crash(tmp_path, seed):
    import random
    rng = random.Random(seed)
    for _ in range(40):
        table = dict(GOOD)
        for key in rng.sample(sorted(table), rng.randint(1, 3)):
            table[key] = rng.choice(VALUES)
        if rng.random() < 0.2:
            table[rng.choice(["file", "raw", "dims", "bogus"])] = rng.choice(VALUES)
        text = "\n".join(f"{k} = {v}" for k, v in table.items())
        try:
            scene = load(tmp_path, text)
        except ReaderError as error:
            assert "volume[1]" in str(error) or "TOML" in str(error), str(error)
            continue
        (volume,) = volumes_of(scene)
        assert np.all(np.isfinite(volume.values))
        settings = RenderSettings.for_scene(scene, renderer="volume", size=(6, 5))
        frame = render(scene, scene.views[0], settings)
        assert frame.color.shape == (5, 6, 3)


@pytest.mark.parametrize("spacing", [["0.5"], ["1", "2", "3"]])
def test_a_dicom_pixel_spacing_that_is_not_two_numbers_is_one_line(tmp_path, spacing):
    pydicom = need_module("pydicom", "DICOM series are read through pydicom")
    paths = ct_series(tmp_path / "ct")
    for path in paths:
        ds = pydicom.dcmread(path)
        ds.PixelSpacing = spacing
        ds.save_as(path)
    message = refused(tmp_path, 'file = "ct"\nmode = "mip"')
    assert "PixelSpacing must be two numbers (row and column spacing)" in message


def test_a_nifti_header_nibabel_refuses_is_one_line(tmp_path):
    image = nibabel.Nifti1Image(np.ones((4, 4, 4), np.float32), np.eye(4))
    path = tmp_path / "v.nii"
    nibabel.save(image, str(path))
    raw = bytearray(path.read_bytes())
    raw[70:72] = (999).to_bytes(2, "little")          # datatype 999: no such code
    path.write_bytes(bytes(raw))
    message = refused(tmp_path, 'file = "v.nii"\nmode = "mip"')
    assert "not a readable NIfTI file" in message


@pytest.mark.parametrize("center", ["[0, 0]", "{ x = 1 }"])
def test_a_generator_param_of_the_wrong_shape_is_one_line(tmp_path, center):
    message = refused(tmp_path, f'generator = "sphere"\nparams = {{ size = 16, center = '
                                f'{center} }}\nmode = "mip"')
    assert "center must be three finite numbers [x, y, z] within" in message


def test_a_dicom_rescale_slope_past_float32_is_one_line_and_no_warning(tmp_path):
    import warnings
    pydicom = need_module("pydicom", "DICOM series are read through pydicom")
    paths = ct_series(tmp_path / "ct")
    for path in paths:
        ds = pydicom.dcmread(path)
        ds.RescaleSlope = "1e308"
        ds.save_as(path)
    with warnings.catch_warnings():
        warnings.simplefilter("error")                      # no RuntimeWarning reaches anyone
        message = refused(tmp_path, 'file = "ct"\nmode = "mip"')
    assert "RescaleSlope 1e+308 and RescaleIntercept" in message


@pytest.mark.parametrize("key, value", [("ImageOrientationPatient", ["nan", 0, 0, 0, 1, 0]),
                                        ("ImagePositionPatient", [0, "nan", 0])])
def test_a_nan_dicom_orientation_or_position_names_the_slice_and_the_tag(tmp_path, key, value):
    pydicom = need_module("pydicom", "DICOM series are read through pydicom")
    paths = ct_series(tmp_path / "ct")
    import warnings
    ds = pydicom.dcmread(paths[1])
    with warnings.catch_warnings():             # pydicom says 'nan' is no DS: the test's own
        warnings.simplefilter("ignore", UserWarning)
        setattr(ds, key, value)
        ds.save_as(paths[1])
    with warnings.catch_warnings():
        warnings.simplefilter("error")          # the reader lets no warning reach the user
        message = refused(tmp_path, 'file = "ct"\nmode = "mip"')
    assert f"{paths[1].name}: {key} must be" in message and "finite numbers" in message
