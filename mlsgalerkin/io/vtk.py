"""VTU particle snapshots and ParaView ``.pvd`` time series (via meshio).

A frame is an unstructured grid of ``vertex`` cells, one per particle, with per-particle
``point_data``. VTK always stores three coordinates and vectors of three components, so 2D
data are padded with zeros in the file:

=====================  ====================  =====================================
array passed           stored as             note
=====================  ====================  =====================================
points ``(n, 2)``      ``(n, 3)``            ``z = 0``
scalar ``(n,)``        ``(n,)``
vector ``(n, 2)``      ``(n, 3)``            third component 0
vector ``(n, 3)``      ``(n, 3)``
tensor ``(n, d, d)``   ``(n, d*d)``          row-major; ParaView shows 9 as tensor
=====================  ====================  =====================================

``bool`` arrays are stored as ``uint8`` (0/1), ``float16`` as ``float32``; other integer and
float dtypes are stored as they are. Files are written to a temporary name and moved into
place (:func:`~mlsgalerkin.io.files.atomic_output`).

:class:`PVDSeries` writes ``name_00000.vtu, name_00001.vtu, ...`` and after each frame
rewrites ``name.pvd``, the ParaView collection that lists every frame with its time (written
with ``repr``, so exactly) and its file name relative to the ``.pvd``.

>>> print(pvd_xml([(0.0, "p_00000.vtu"), (0.5, "p_00001.vtu")]), end="")
<?xml version="1.0"?>
<VTKFile type="Collection" version="0.1" byte_order="LittleEndian">
  <Collection>
    <DataSet timestep="0.0" group="" part="0" file="p_00000.vtu"/>
    <DataSet timestep="0.5" group="" part="0" file="p_00001.vtu"/>
  </Collection>
</VTKFile>
"""

from __future__ import annotations

import logging
import math
import re
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import Mapping, Sequence
from xml.sax.saxutils import quoteattr

import numpy as np

from mlsgalerkin.io.files import atomic_output, atomic_write

__all__ = ["PVDSeries", "pvd_xml", "read_pvd", "read_vtu", "vtm_xml", "write_multiblock_series", "write_vtu"]

logger = logging.getLogger(__name__)

_VTU_DTYPES = {
    np.dtype(t)
    for t in ("float32", "float64", "int8", "int16", "int32", "int64",
              "uint8", "uint16", "uint32", "uint64")
}


def _as_points(points: np.ndarray, what: str = "points") -> np.ndarray:
    pts = np.asarray(points)
    if pts.ndim != 2 or pts.shape[1] not in (2, 3):
        raise ValueError(f"{what} must have shape (n, 2) or (n, 3), got {pts.shape}")
    if pts.shape[0] == 0:
        raise ValueError(f"{what} is empty: a VTU frame needs at least one point")
    if not np.issubdtype(pts.dtype, np.number) or np.iscomplexobj(pts):
        raise ValueError(f"{what} must be a real float array, got dtype {pts.dtype}")
    return pts.astype(np.float64, copy=False)


def _vtu_array(name: str, value: np.ndarray, n: int, d: int) -> np.ndarray:
    """One ``point_data`` entry in the layout and dtype the VTU file stores."""
    arr = np.asarray(value)
    if arr.dtype == np.bool_:
        arr = arr.astype(np.uint8)
    elif arr.dtype == np.float16:
        arr = arr.astype(np.float32)
    elif arr.dtype.byteorder not in ("=", "|") and arr.dtype.newbyteorder("=") in _VTU_DTYPES:
        arr = arr.astype(arr.dtype.newbyteorder("="))
    if arr.dtype not in _VTU_DTYPES:
        raise ValueError(
            f"point_data[{name!r}] has dtype {arr.dtype}; VTU stores bool, int8..int64, "
            "uint8..uint64, float32 or float64 only: convert it (e.g. .astype(float))"
        )
    if arr.ndim == 0 or arr.shape[0] != n:
        raise ValueError(
            f"point_data[{name!r}] has shape {arr.shape} but there are {n} points; its first "
            "axis must be the point index"
        )
    if arr.ndim == 1:
        return arr
    if arr.ndim == 2 and arr.shape[1] == d:
        if d == 2:
            arr = np.concatenate([arr, np.zeros((n, 1), dtype=arr.dtype)], axis=1)
        return arr
    if arr.ndim == 3 and arr.shape[1:] == (d, d):
        return arr.reshape(n, d * d)
    raise ValueError(
        f"point_data[{name!r}] has shape {arr.shape}; with {n} points in {d}D expected a "
        f"scalar ({n},), a vector ({n}, {d}) or a tensor ({n}, {d}, {d})"
    )


def write_vtu(
    path: str | Path, points: np.ndarray, point_data: Mapping[str, np.ndarray] | None = None,
    cells: Sequence[tuple[str, np.ndarray]] | None = None,
) -> Path:
    """Write a particle point cloud as a VTU file (atomically) and return its path.

    Parameters
    ----------
    path : str or Path
        Target ``.vtu`` file; its directory must exist.
    points : ndarray, shape (n, d), d in {2, 3}
        Particle positions [m], ``n >= 1``. 2D points get ``z = 0`` in the file.
    point_data : dict of str to ndarray, optional
        Per-particle fields: scalars ``(n,)``, vectors ``(n, d)`` (padded to 3 components) or
        tensors ``(n, d, d)`` (flattened row-major to ``(n, d*d)``). ``bool`` is stored as
        ``uint8``. Units are the caller's (the file records none).
    cells : list of (meshio cell type, (k, m) int array), optional
        Cells on the points (``"quad"``, ``"triangle"``, ``"line"``: a structure's mesh); a point
        cloud of ``vertex`` cells without them.

    Returns
    -------
    Path
        ``path``.
    """
    import meshio  # lazy: keeps `import mlsgalerkin` fast

    path = Path(path)
    pts = _as_points(points)
    n, d = pts.shape
    data = {}
    for name, value in (point_data or {}).items():
        if not isinstance(name, str) or not name:
            raise ValueError(f"point_data key {name!r} must be a non-empty str")
        data[name] = _vtu_array(name, value, n, d)
    if d == 2:
        pts = np.concatenate([pts, np.zeros((n, 1))], axis=1)
    blocks = [("vertex", np.arange(n, dtype=np.int64).reshape(n, 1))] if not cells else \
        [(kind, np.ascontiguousarray(np.asarray(c, dtype=np.int64))) for kind, c in cells]
    mesh = meshio.Mesh(
        np.ascontiguousarray(pts),
        blocks,
        point_data={k: np.ascontiguousarray(v) for k, v in data.items()},
    )
    with atomic_output(path) as tmp:
        meshio.write(tmp, mesh, file_format="vtu")
    logger.debug("wrote %s (%d points, %d fields)", path, n, len(data))
    return path


def read_vtu(path: str | Path) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """Read a VTU file (e.g. one written by :func:`write_vtu`).

    Returns
    -------
    points : ndarray, shape (n, 3)
        Always three columns, as stored: 2D data come back with ``z = 0``; use
        ``points[:, :2]`` for the original 2D positions.
    point_data : dict of str to ndarray
        Arrays as stored in the file: 2D vectors as ``(n, 3)`` with a zero third component,
        tensors flattened to ``(n, d*d)``, ``bool`` as ``uint8``.
    """
    import meshio

    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"VTU file {path} does not exist")
    mesh = meshio.read(path, file_format="vtu")
    return np.asarray(mesh.points, dtype=np.float64), dict(mesh.point_data)


# ------------------------------------------------------------------------------------------
# .pvd collections
# ------------------------------------------------------------------------------------------


def pvd_xml(frames: Sequence[tuple[float, str]]) -> str:
    """The ParaView collection XML listing ``(time, relative file name)`` frames in order."""
    lines = [
        '<?xml version="1.0"?>',
        '<VTKFile type="Collection" version="0.1" byte_order="LittleEndian">',
        "  <Collection>",
    ]
    for t, name in frames:
        lines.append(
            f'    <DataSet timestep="{float(t)!r}" group="" part="0" file={quoteattr(str(name))}/>'
        )
    lines += ["  </Collection>", "</VTKFile>", ""]
    return "\n".join(lines)


def read_pvd(path: str | Path) -> list[tuple[float, Path]]:
    """Frames ``(time, path)`` listed in a ``.pvd`` collection, in file order.

    Relative file names are joined to the ``.pvd``'s directory (``Path(path).parent``).
    """
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"PVD file {path} does not exist")
    try:
        root = ET.parse(path).getroot()
    except ET.ParseError as exc:
        raise ValueError(f"{path} is not valid XML ({exc}); it is not a readable .pvd") from exc
    coll = root.find("Collection")
    if root.tag != "VTKFile" or root.get("type") != "Collection" or coll is None:
        raise ValueError(f"{path} is not a ParaView collection (.pvd) file")
    frames = []
    for ds in coll.findall("DataSet"):
        t, f = ds.get("timestep"), ds.get("file")
        if t is None or f is None:
            raise ValueError(f"{path}: a DataSet lacks its timestep or file attribute")
        frames.append((float(t), path.parent / f))
    return frames


class PVDSeries:
    """A growing series of VTU frames with its ParaView ``.pvd`` collection.

    Parameters
    ----------
    directory : str or Path
        Output directory (created if missing).
    name : str
        Base name: frames are ``directory/{name}_{index:05d}.vtu``, the collection is
        ``directory/{name}.pvd``.

    Examples
    --------
    ``series = PVDSeries("out"); series.add(0.0, x, {"p": p}); series.add(0.01, x, {"p": p})``;
    after a restart at time ``t``: ``series = PVDSeries.resume("out", after_time=t)``.
    """

    def __init__(self, directory: str | Path, name: str = "particles") -> None:
        if not isinstance(name, str) or not name or "/" in name or "\\" in name:
            raise ValueError(f"PVDSeries name must be a plain file-name stem, got {name!r}")
        self.directory = Path(directory)
        self.name = name
        self._frames: list[tuple[float, Path]] = []
        self._next_index = 0

    @property
    def pvd_path(self) -> Path:
        """The collection file ``directory/{name}.pvd``."""
        return self.directory / f"{self.name}.pvd"

    @property
    def frames(self) -> list[tuple[float, Path]]:
        """``(time, path)`` of every frame, in time order (a copy)."""
        return list(self._frames)

    def frame_path(self, index: int) -> Path:
        """Path of frame number ``index``: ``directory/{name}_{index:05d}.vtu``."""
        return self.directory / f"{self.name}_{index:05d}.vtu"

    def add(
        self,
        time: float,
        points: np.ndarray,
        point_data: Mapping[str, np.ndarray] | None = None,
        cells: Sequence[tuple[str, np.ndarray]] | None = None,
    ) -> Path:
        """Write the next frame and rewrite the ``.pvd`` (both atomically).

        Parameters
        ----------
        time : float
            Simulation time [s]; finite and greater than the previous frame's.
        points, point_data, cells
            As for :func:`write_vtu`.

        Returns
        -------
        Path
            The new ``.vtu`` file.
        """
        t = float(time)
        if not math.isfinite(t):
            raise ValueError(f"PVDSeries.add: time must be finite, got {time!r}")
        if self._frames and not t > self._frames[-1][0]:
            raise ValueError(
                f"PVDSeries.add: time {t!r} is not after the last frame's time "
                f"{self._frames[-1][0]!r}; add frames in increasing time (after a restart use "
                "PVDSeries.resume(directory, name, after_time=restart_time))"
            )
        self.directory.mkdir(parents=True, exist_ok=True)
        path = write_vtu(self.frame_path(self._next_index), points, point_data, cells)
        self._frames.append((t, path))
        self._next_index += 1
        self._write_pvd()
        return path

    def _write_pvd(self) -> None:
        entries = []
        for t, p in self._frames:
            try:
                rel = p.relative_to(self.directory).as_posix()
            except ValueError:
                rel = str(p)
            entries.append((t, rel))
        atomic_write(self.pvd_path, pvd_xml(entries))

    @classmethod
    def resume(
        cls, directory: str | Path, name: str = "particles", after_time: float | None = None
    ) -> PVDSeries:
        """Continue an existing series, e.g. in a run restarted from a checkpoint.

        Reads ``directory/{name}.pvd`` and keeps only the frames with ``time <= after_time``
        (all of them if ``after_time`` is None), so frames written after the checkpoint by
        the interrupted run are not listed twice. New frames continue the numbering after the
        last kept frame and overwrite the dropped frames' files. Nothing is written until
        the next :meth:`add`. A missing ``.pvd`` gives an empty series.
        """
        series = cls(directory, name)
        if not series.pvd_path.is_file():
            logger.info("no %s to resume; starting a new series", series.pvd_path)
            return series
        listed = read_pvd(series.pvd_path)
        kept = [(t, p) for t, p in listed if after_time is None or not t > float(after_time)]
        pattern = re.compile(rf"^{re.escape(name)}_(\d+)\.vtu$")
        indices = [int(m.group(1)) for _, p in kept if (m := pattern.match(p.name))]
        series._frames = kept
        series._next_index = max(indices) + 1 if indices else len(kept)
        if len(kept) < len(listed):
            logger.info("resuming %s: dropped %d frame(s) after t = %r",
                        series.pvd_path, len(listed) - len(kept), after_time)
        return series


def vtm_xml(blocks: Sequence[tuple[str, str]]) -> str:
    """A VTK multiblock (``.vtm``) file listing ``(block name, relative .vtu file)`` blocks."""
    lines = ['<?xml version="1.0"?>', '<VTKFile type="vtkMultiBlockDataSet" version="1.0" byte_order="LittleEndian">',
             "  <vtkMultiBlockDataSet>"]
    for k, (name, file) in enumerate(blocks):
        lines.append(f"    <DataSet index={quoteattr(str(k))} name={quoteattr(name)} file={quoteattr(file)}/>")
    lines += ["  </vtkMultiBlockDataSet>", "</VTKFile>", ""]
    return "\n".join(lines)


def write_multiblock_series(directory: str | Path, series: Mapping[str, PVDSeries], name: str = "frames") -> Path:
    """One series of several systems' frames: ``{name}_{index:05d}.vtm`` per frame time, a block
    per series (the particles, the structures), and ``{name}.pvd`` listing them (ParaView opens
    it as one time series). Frames are matched by time; rewritten atomically; returns the ``.pvd``."""
    directory = Path(directory)
    times: dict[float, list[tuple[str, str]]] = {}
    for block, s in series.items():
        for t, p in s.frames:
            times.setdefault(round(float(t), 12), []).append((block, p.name))
    entries = []
    for k, (t, blocks) in enumerate(sorted(times.items())):
        file = f"{name}_{k:05d}.vtm"
        atomic_write(directory / file, vtm_xml(blocks))
        entries.append((t, file))
    pvd = directory / f"{name}.pvd"
    atomic_write(pvd, pvd_xml(entries))
    return pvd
