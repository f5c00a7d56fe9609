"""Volume files → ``(values (nx, ny, nz), spacing)``, each refusing malformed input with one
message that names the file and what is wrong, before it allocates more than the header
promises (:data:`core.volume.data.MAX_VOXELS`).

- :func:`read_raw`: bare samples with a small header table given in the scene (``dims``,
  ``dtype``, ``byte_order``, ``offset``): x varies fastest, then y, then z (the order of NRRD
  and of most scanners' raw dumps); the file's size must be exactly ``offset + nx·ny·nz·size``;
- :func:`read_nrrd`: NRRD through ``pynrrd`` (header first: its ``sizes`` are checked against
  the budget, and for raw encoding against the file's size, before the data is read);
- :func:`read_nifti`: NIfTI-1 or -2 through ``nibabel`` (its header's shape and the file's
  size checked first; a fourth axis of one sample is dropped, more is refused);
- :func:`read_dicom`: a DICOM series, a folder of slices, through ``pydicom`` (the headers
  first: one size and orientation, even steps along the slice normal, no missing slice).

The samples then pass :func:`core.volume.data.checked_samples` (NaN and infinity refused).
"""

from __future__ import annotations

import gzip
import logging
import math
import stat
import warnings
from pathlib import Path

import numpy as np

from core.volume.data import VolumeError, check_dims, check_spacing, checked_samples

DTYPES = ("uint8", "int8", "uint16", "int16", "uint32", "int32", "float32", "float64")
BYTE_ORDERS = ("little", "big")
EXTENSIONS = (".raw", ".nrrd", ".nhdr", ".nii", ".nii.gz", "a folder of DICOM slices")


def kind_of(path: str | Path, folder: Path | None = None) -> str:
    """The reader for ``path``: by its extension, or ``"dicom"`` for a folder (a series)."""
    if folder is not None and (folder / path).is_dir():
        return "dicom"
    name = str(path).lower()
    for ext, kind in ((".nii.gz", "nifti"), (".nii", "nifti"), (".nrrd", "nrrd"),
                      (".nhdr", "nrrd"), (".raw", "raw")):
        if name.endswith(ext):
            return kind
    raise VolumeError(f"{path}: not a volume file type we read ({', '.join(EXTENSIONS)})")


def file_size(path: Path, shown: str) -> int:
    """The size of ``path``, a regular file (a FIFO would block the reader for ever, a device
    such as /dev/zero never end): else one clear VolumeError."""
    try:
        mode = path.stat()
    except OSError as error:
        raise VolumeError(f"{shown}: cannot be read ({error.strerror or error})") from None
    if not stat.S_ISREG(mode.st_mode):
        what = ("a FIFO (named pipe)" if stat.S_ISFIFO(mode.st_mode) else "a device"
                if stat.S_ISCHR(mode.st_mode) or stat.S_ISBLK(mode.st_mode) else
                "a folder" if stat.S_ISDIR(mode.st_mode) else "not a regular file")
        raise VolumeError(f"{shown}: is {what}: volumes are read from regular files only")
    return mode.st_size


def read_raw(path: Path, dims, dtype: str = "uint8", byte_order: str = "little",
             offset: int = 0, shown: str | None = None):
    shown = shown or str(path)
    dims = check_dims(dims, f"{shown}: dims")
    if dtype not in DTYPES:
        raise VolumeError(f"{shown}: dtype must be one of {', '.join(DTYPES)}, not {dtype!r}")
    if byte_order not in BYTE_ORDERS:
        raise VolumeError(f"{shown}: byte_order must be little or big, not {byte_order!r}")
    kind = np.dtype(dtype).newbyteorder("<" if byte_order == "little" else ">")
    need = offset + math.prod(dims) * kind.itemsize
    have = file_size(path, shown)
    if have != need:
        what = "is truncated" if have < need else "is longer than its dims say"
        raise VolumeError(f"{shown}: the file {what}: it has {have} bytes, and dims "
                          f"{' x '.join(map(str, dims))} of {dtype} after {offset} header "
                          f"bytes need {need}")
    data = np.fromfile(path, dtype=kind, count=math.prod(dims), offset=offset)
    return checked_samples(data.reshape(dims[::-1]).transpose(2, 1, 0), shown)


def read_nrrd(path: Path, shown: str | None = None):
    import nrrd                                  # pynrrd: only when an NRRD file is read
    shown = shown or str(path)
    file_size(path, shown)                       # a regular file, before it is opened
    try:
        with open(path, "rb") as fh:
            header = nrrd.read_header(fh)
            dims = check_dims([int(s) for s in header.get("sizes", [])], shown)
            _check_nrrd_skips(path, header, shown)
            _check_nrrd_size(path, header, dims, fh.tell(), shown)
            data = nrrd.read_data(header, fh, str(path), index_order="F")
    except VolumeError:
        raise
    except (nrrd.NRRDError, OSError, ValueError, EOFError, gzip.BadGzipFile) as error:
        raise VolumeError(f"{shown}: not a readable NRRD file (truncated or malformed: "
                          f"{error})") from None
    if data.shape != dims:
        raise VolumeError(f"{shown}: the data holds {data.size} samples, its header's sizes "
                          f"{' x '.join(map(str, dims))} say {math.prod(dims)}")
    return checked_samples(data, shown), _nrrd_spacing(header, shown)


MAX_LINE_SKIP = 100_000         # header lines an NRRD may ask to skip before its data


def _check_nrrd_skips(path: Path, header: dict, shown: str) -> None:
    """``line skip`` and ``byte skip`` within reach, and a detached ``data file`` a regular
    file (pynrrd would read a line at a time 10^10 times, or block on a FIFO)."""
    try:
        lines = int(header.get("line skip", 0))
        skip = int(header.get("byte skip", 0))
    except (TypeError, ValueError):
        raise VolumeError(f"{shown}: line skip and byte skip must be whole numbers") from None
    if not 0 <= lines <= MAX_LINE_SKIP:
        raise VolumeError(f"{shown}: line skip {lines} is beyond reach (0 to {MAX_LINE_SKIP:,})")
    detached = header.get("data file")
    data = path if detached is None else path.parent / str(detached).strip()
    if detached is not None and str(detached).strip().upper().startswith("LIST"):
        return                                   # pynrrd reads the listed files itself
    if detached is not None:
        file_size(data, f"{shown}: data file {str(detached).strip()}")
    if skip > file_size(data, shown):
        raise VolumeError(f"{shown}: byte skip {skip} is past the end of the data file")


def _check_nrrd_size(path: Path, header: dict, dims, data_start: int, shown: str) -> None:
    """Raw-encoded data in the same file must be exactly there (the header's sizes × type),
    and gzip-encoded data must inflate to no more than that: a 6 MB stream of 6 GiB of zeros
    is refused after the bytes the sizes need, not inflated whole."""
    encoding = str(header.get("encoding", "raw")).strip().lower()
    itemsize = NRRD_SIZES.get(str(header.get("type", "")).strip().lower())
    if itemsize is None:
        return                                  # pynrrd names the type it does not know
    want = math.prod(dims) * itemsize
    detached = "data file" in header
    data, start = (path.parent / str(header["data file"]).strip(), 0) if detached else \
        (path, data_start)
    if encoding == "raw" and not detached and int(header.get("byte skip", 0)) == 0 \
            and int(header.get("line skip", 0)) == 0:
        have = file_size(path, shown)
        if have != data_start + want:
            what = "is truncated" if have < data_start + want else "is longer than its sizes say"
            raise VolumeError(f"{shown}: the file {what}: it has {have} bytes, and sizes "
                              f"{' x '.join(map(str, dims))} need {data_start + want}")
    elif encoding in ("gzip", "gz"):
        _check_inflated(data, start, want, shown)


def _check_inflated(path: Path, start: int, want: int, shown: str) -> None:
    """The gzip stream from byte ``start`` of ``path`` inflates to at most ``want`` bytes
    (read a chunk at a time, never more than that kept)."""
    import zlib
    inflate = zlib.decompressobj(zlib.MAX_WBITS | 16)
    made = 0
    with open(path, "rb") as fh:
        fh.seek(start)
        while chunk := fh.read(1 << 20):
            while chunk:
                try:
                    made += len(inflate.decompress(chunk, 1 << 24))
                except zlib.error as error:
                    raise VolumeError(f"{shown}: the gzip data cannot be read ({error})") \
                        from None
                if made > want:
                    raise VolumeError(f"{shown}: the gzip data inflates past the {want:,} "
                                      f"bytes its sizes need: refused before it fills memory")
                chunk = inflate.unconsumed_tail
            if inflate.eof:
                return


# Bytes per sample of each NRRD type name (the format's own spellings).
NRRD_SIZES = {**dict.fromkeys(("signed char", "int8", "int8_t", "uchar", "unsigned char",
                               "uint8", "uint8_t"), 1),
              **dict.fromkeys(("short", "short int", "signed short", "signed short int",
                               "int16", "int16_t", "ushort", "unsigned short",
                               "unsigned short int", "uint16", "uint16_t"), 2),
              **dict.fromkeys(("int", "signed int", "int32", "int32_t", "uint", "unsigned int",
                               "uint32", "uint32_t", "float"), 4),
              **dict.fromkeys(("longlong", "long long", "long long int", "signed long long",
                               "signed long long int", "int64", "int64_t", "ulonglong",
                               "unsigned long long", "unsigned long long int", "uint64",
                               "uint64_t", "double"), 8)}


def _nrrd_spacing(header: dict, shown: str):
    if "spacings" in header:
        return check_spacing(header["spacings"], f"{shown}: spacings")
    directions = header.get("space directions")
    if directions is not None:
        rows = np.asarray(directions, dtype=np.float64)
        if rows.shape == (3, 3) and np.all(np.isfinite(rows)):
            return check_spacing(np.linalg.norm(rows, axis=1), f"{shown}: space directions")
    return (1.0, 1.0, 1.0)


def read_nifti(path: Path, shown: str | None = None):
    import nibabel                              # only when a NIfTI file is read
    shown = shown or str(path)
    file_size(path, shown)
    quiet = logging.getLogger("nibabel")         # its "sizeof_hdr should be 348" lines: our
    quiet.setLevel(logging.CRITICAL)             # one error line says what is wrong instead
    try:
        image = nibabel.load(str(path))
        shape = tuple(int(n) for n in image.header.get_data_shape())
        if len(shape) == 4 and shape[3] == 1:
            shape = shape[:3]
        dims = check_dims(shape, shown)
        _check_nifti_size(path, image, dims, shown)
        data = np.asanyarray(image.dataobj).reshape(dims)
        zooms = image.header.get_zooms()[:3]
    except VolumeError:
        raise
    except (nibabel.filebasedimages.ImageFileError, nibabel.spatialimages.HeaderDataError,
            OSError, ValueError, EOFError, gzip.BadGzipFile) as error:
        raise VolumeError(f"{shown}: not a readable NIfTI file (truncated or malformed: "
                          f"{error})") from None
    return checked_samples(data, shown), check_spacing(zooms, f"{shown}: voxel sizes")


def _check_nifti_size(path: Path, image, dims, shown: str) -> None:
    if str(path).lower().endswith(".gz"):
        return                                  # nibabel finds a short gzip stream itself
    header = image.header
    offset = int(getattr(image.dataobj, "offset", header.get_data_offset()))  # where data starts
    need = offset + math.prod(dims) * header.get_data_dtype().itemsize
    have = file_size(path, shown)
    if have < need:
        raise VolumeError(f"{shown}: the file is truncated: it has {have} bytes, and its "
                          f"header's shape {' x '.join(map(str, dims))} needs {need}")


# A gap between neighbouring slices this many times the series' usual one is a missing slice.
MISSING_GAP = 1.5


def read_dicom(folder: Path, shown: str | None = None):
    """A DICOM series: every file of ``folder`` is one slice (pydicom). The headers are read
    first (no pixels): the slices must share their size and orientation, lie on one line along
    the slice normal at even steps (a gap of more than 1.5 steps is a missing slice), and fit
    the budget; then the pixels, rescaled (``RescaleSlope``, ``RescaleIntercept``). Columns run
    along x, rows along y, slices along z."""
    import pydicom                               # only when a DICOM series is read
    from pydicom.errors import InvalidDicomError
    shown = shown or str(folder)
    files = sorted(p for p in Path(folder).iterdir() if p.is_file()) if Path(folder).is_dir() \
        else []
    if len(files) < 2:
        raise VolumeError(f"{shown}: a DICOM series is a folder of at least 2 slice files, "
                          f"found {len(files)}")
    logging.getLogger("pydicom").setLevel(logging.CRITICAL)    # our one line says it instead
    try:
        with warnings.catch_warnings():       # an invalid value's warning: checked below
            warnings.simplefilter("ignore", UserWarning)
            headers = [pydicom.dcmread(p, stop_before_pixels=True) for p in files]
        slices = _dicom_order(headers, files, shown)
        rows, cols = int(headers[0].Rows), int(headers[0].Columns)
        check_dims((cols, rows, len(slices)), shown)
        pixels = np.empty((cols, rows, len(slices)), np.float32)
        for k, (path, ds) in enumerate(slices):
            image = pydicom.dcmread(path).pixel_array
            if image.shape != (rows, cols):
                raise VolumeError(f"{shown}: {path.name} holds a {image.shape} image, not "
                                  f"{rows} x {cols}")
            slope, intercept = float(ds.get("RescaleSlope", 1)), float(ds.get("RescaleIntercept", 0))
            with np.errstate(over="ignore", invalid="ignore"):    # judged just below
                rescaled = (image.astype(np.float64) * slope + intercept).T
            if not (np.all(np.abs(rescaled) <= np.finfo(np.float32).max)):
                raise VolumeError(f"{shown}: {path.name}: RescaleSlope {slope:g} and "
                                  f"RescaleIntercept {intercept:g} take its values beyond "
                                  f"what a sample holds")
            pixels[:, :, k] = rescaled
    except VolumeError:
        raise
    except (InvalidDicomError, AttributeError, KeyError, OSError, ValueError, TypeError,
            RuntimeError, NotImplementedError) as error:
        raise VolumeError(f"{shown}: not a readable DICOM series ({type(error).__name__}: "
                          f"{error})") from None
    gaps = np.diff([position for position, _ in _positions(slices)])
    spacing = _pixel_spacing(headers[0], files[0], shown) + (float(np.median(gaps)),)
    return checked_samples(pixels, shown), check_spacing(spacing, f"{shown}: spacing")


def _pixel_spacing(ds, path: Path, shown: str) -> tuple[float, float]:
    """(column, row) spacing from PixelSpacing (row, column): two numbers, else one line."""
    try:
        row, column = (float(s) for s in ds.PixelSpacing)
    except (TypeError, ValueError):
        raise VolumeError(f"{shown}: {path.name}: PixelSpacing must be two numbers (row and "
                          f"column spacing), not {ds.PixelSpacing!r}") from None
    return column, row


def _positions(slices):
    ds = slices[0][1]
    row, col = np.asarray(ds.ImageOrientationPatient, dtype=np.float64).reshape(2, 3)
    normal = np.cross(row, col)
    return [(float(np.asarray(s.ImagePositionPatient, dtype=np.float64) @ normal), s)
            for _, s in slices]


def _dicom_order(headers, files, shown):
    """The slices sorted along the slice normal; refuses mixed sizes or orientations,
    two slices at one position and a missing slice."""
    first = headers[0]
    for path, ds in zip(files, headers):
        for key in ("Rows", "Columns", "ImageOrientationPatient", "ImagePositionPatient",
                    "PixelSpacing"):
            if key not in ds:
                raise VolumeError(f"{shown}: {path.name} has no {key}")
        for key, count in (("ImageOrientationPatient", 6), ("ImagePositionPatient", 3)):
            try:
                values = np.asarray(ds[key].value, dtype=np.float64).reshape(-1)
            except (TypeError, ValueError):
                values = np.array([])
            if values.size != count or not np.all(np.isfinite(values)):
                raise VolumeError(f"{shown}: {path.name}: {key} must be {count} finite numbers, "
                                  f"not {ds[key].value!r}")
        if (ds.Rows, ds.Columns) != (first.Rows, first.Columns) or not np.allclose(
                ds.ImageOrientationPatient, first.ImageOrientationPatient, atol=1e-4):
            raise VolumeError(f"{shown}: {path.name} is not of the series' size and "
                              f"orientation ({first.Rows} x {first.Columns})")
    placed = sorted(_positions(list(zip(files, headers))), key=lambda pair: pair[0])
    by_header = {id(ds): path for path, ds in zip(files, headers)}
    slices = [(by_header[id(ds)], ds) for _, ds in placed]
    along = np.array([position for position, _ in placed])
    gaps = np.diff(along)
    if np.any(gaps <= 1e-6):
        k = int(np.argmax(gaps <= 1e-6))
        raise VolumeError(f"{shown}: {slices[k][0].name} and {slices[k + 1][0].name} lie at "
                          f"one position ({along[k]:g} mm along the slice normal)")
    step = float(np.median(gaps))
    if np.any(gaps > MISSING_GAP * step):
        k = int(np.argmax(gaps > MISSING_GAP * step))
        raise VolumeError(f"{shown}: a slice is missing between {slices[k][0].name} "
                          f"({along[k]:g} mm) and {slices[k + 1][0].name} ({along[k + 1]:g} "
                          f"mm): a gap of {gaps[k]:g} mm where the slices are {step:g} mm "
                          f"apart")
    return slices
