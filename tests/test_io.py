"""Output package: VTU/PVD round trips, checkpoints, CSV time series, atomicity (pictures: test_render_pictures.py)."""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pytest

from mlsgalerkin import io as mio
from mlsgalerkin.io import checkpoint as ckpt


def _leftovers(directory: Path) -> list[str]:
    """Temporary files left behind by an interrupted atomic write."""
    return sorted(p.name for p in directory.iterdir() if p.name.endswith(".tmp"))


# ----------------------------------------------------------------------------------------
# VTU
# ----------------------------------------------------------------------------------------


@pytest.mark.parametrize("d", [2, 3])
def test_vtu_round_trip_scalars_vectors_tensors(tmp_path, rng, d):
    n = 7
    x = rng.random((n, d))
    data = {
        "p": rng.standard_normal(n),
        "v": rng.standard_normal((n, d)),
        "sigma": rng.standard_normal((n, d, d)),
        "id": np.arange(n, dtype=np.int32),
        "wall": np.arange(n) % 2 == 0,
        "rho32": rng.random(n).astype(np.float32),
    }
    path = mio.write_vtu(tmp_path / "f.vtu", x, data)
    assert path == tmp_path / "f.vtu"
    pts, back = mio.read_vtu(path)

    assert pts.shape == (n, 3)
    np.testing.assert_array_equal(pts[:, :d], x)  # binary: exact
    if d == 2:
        np.testing.assert_array_equal(pts[:, 2], 0.0)
    np.testing.assert_array_equal(back["p"], data["p"])
    assert back["v"].shape == (n, 3)
    np.testing.assert_array_equal(back["v"][:, :d], data["v"])
    if d == 2:
        np.testing.assert_array_equal(back["v"][:, 2], 0.0)
    np.testing.assert_array_equal(back["sigma"], data["sigma"].reshape(n, d * d))
    assert back["id"].dtype == np.int32
    np.testing.assert_array_equal(back["id"], data["id"])
    assert back["wall"].dtype == np.uint8
    np.testing.assert_array_equal(back["wall"], data["wall"].astype(np.uint8))
    assert back["rho32"].dtype == np.float32
    np.testing.assert_array_equal(back["rho32"], data["rho32"])
    assert _leftovers(tmp_path) == []


def test_vtu_is_readable_by_vtk_itself(tmp_path, rng):
    vtk = pytest.importorskip("vtkmodules.vtkIOXML")
    x = rng.random((5, 2))
    mio.write_vtu(tmp_path / "f.vtu", x, {"u": rng.random((5, 2)), "p": rng.random(5)})
    reader = vtk.vtkXMLUnstructuredGridReader()
    reader.SetFileName(str(tmp_path / "f.vtu"))
    reader.Update()
    grid = reader.GetOutput()
    assert grid.GetNumberOfPoints() == 5 and grid.GetNumberOfCells() == 5
    assert grid.GetPointData().GetArray("u").GetNumberOfComponents() == 3
    assert grid.GetPointData().GetArray("p").GetNumberOfComponents() == 1


@pytest.mark.parametrize(
    ("points", "data", "match"),
    [
        (np.zeros((4, 2)), {"p": np.zeros(3)}, r"point_data\['p'\].*4 points"),
        (np.zeros((4, 2)), {"v": np.zeros((4, 3))}, r"vector \(4, 2\)"),
        (np.zeros((4, 3)), {"t": np.zeros((4, 2, 2))}, r"tensor \(4, 3, 3\)"),
        (np.zeros((4, 1)), {}, r"shape \(n, 2\) or \(n, 3\)"),
        (np.zeros((0, 2)), {}, "empty"),
        (np.zeros((2, 2)), {"o": np.array([{}, {}], dtype=object)}, "dtype object"),
        (np.zeros((2, 2)), {"c": np.zeros(2, dtype=complex)}, "dtype complex"),
    ],
)
def test_write_vtu_rejects_bad_input_with_a_clear_message(tmp_path, points, data, match):
    with pytest.raises(ValueError, match=match):
        mio.write_vtu(tmp_path / "bad.vtu", points, data)
    assert not (tmp_path / "bad.vtu").exists()


def test_failed_vtu_write_keeps_the_previous_file_and_no_temp_file(tmp_path, monkeypatch):
    import meshio

    target = tmp_path / "f.vtu"
    mio.write_vtu(target, np.zeros((3, 2)), {"p": np.ones(3)})
    before = target.read_bytes()

    def broken_write(filename, mesh, file_format=None, **kw):
        Path(filename).write_bytes(b"<?xml half a file")  # dies midway
        raise OSError("disk full")

    monkeypatch.setattr(meshio, "write", broken_write)
    with pytest.raises(OSError, match="disk full"):
        mio.write_vtu(target, np.zeros((3, 2)), {"p": np.zeros(3)})
    assert target.read_bytes() == before
    assert _leftovers(tmp_path) == []


# ----------------------------------------------------------------------------------------
# PVD series
# ----------------------------------------------------------------------------------------


def _frame(k: int, n: int = 4) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    x = np.column_stack([np.linspace(0, 1, n) + 0.1 * k, np.zeros(n)])
    return x, {"p": np.full(n, float(k)), "u": np.tile([1.0 * k, 0.0], (n, 1))}


def test_pvd_series_lists_frames_in_order_with_exact_times(tmp_path):
    out = tmp_path / "out"
    series = mio.PVDSeries(out)
    times = [0.0, 0.1 + 0.2, 1.0 / 3.0]
    for k, t in enumerate(times):
        path = series.add(t, *_frame(k))
        assert path == out / f"particles_{k:05d}.vtu" and path.is_file()
    assert [t for t, _ in series.frames] == times

    root = ET.parse(out / "particles.pvd").getroot()
    assert root.tag == "VTKFile" and root.get("type") == "Collection"
    sets = root.find("Collection").findall("DataSet")
    assert [ds.get("file") for ds in sets] == [f"particles_{k:05d}.vtu" for k in range(3)]
    assert [float(ds.get("timestep")) for ds in sets] == times  # bit-exact
    assert mio.read_pvd(out / "particles.pvd") == series.frames
    assert _leftovers(out) == []

    with pytest.raises(ValueError, match="increasing time"):
        series.add(times[-1], *_frame(9))


def test_pvd_resume_drops_later_frames_and_continues_without_duplicates(tmp_path):
    series = mio.PVDSeries(tmp_path, name="fluid")
    for k in range(4):
        series.add(0.5 * k, *_frame(k))  # t = 0, 0.5, 1.0, 1.5

    resumed = mio.PVDSeries.resume(tmp_path, "fluid", after_time=0.5)
    assert [t for t, _ in resumed.frames] == [0.0, 0.5]
    new = resumed.add(0.75, *_frame(7))
    assert new.name == "fluid_00002.vtu"
    listed = mio.read_pvd(tmp_path / "fluid.pvd")
    assert [t for t, _ in listed] == [0.0, 0.5, 0.75]
    assert [p.name for _, p in listed] == ["fluid_00000.vtu", "fluid_00001.vtu",
                                          "fluid_00002.vtu"]
    _, data = mio.read_vtu(new)
    np.testing.assert_array_equal(data["p"], 7.0)  # the stale frame 2 was overwritten

    everything = mio.PVDSeries.resume(tmp_path, "fluid")
    assert len(everything.frames) == 3
    assert mio.PVDSeries.resume(tmp_path / "nowhere", "fluid").frames == []


# ----------------------------------------------------------------------------------------
# checkpoints
# ----------------------------------------------------------------------------------------


def _arrays(rng) -> dict[str, np.ndarray]:
    x = rng.standard_normal((50, 2))
    x[0, 0], x[0, 1], x[1, 0], x[1, 1] = np.nan, -0.0, np.inf, 5e-324  # nasty floats
    return {
        "x": x,
        "m": rng.random(50).astype(np.float32),
        "id": np.arange(50, dtype=np.int32),
        "active": rng.random(50) > 0.5,
        "tag": np.array(["wall", "fluid"]),
        "scalar": np.array(3.5),
    }


def _meta() -> dict:
    return {
        "t": 0.1 + 0.2,
        "dt": np.float64(1.0) / 3.0,
        "step": np.int64(1234),
        "done": np.bool_(False),
        "tiny": 5e-324,
        "nan": math.nan,
        "inf": -math.inf,
        "scheme": "symplectic",
        "nested": {"h": [0.01, 0.02], "tuple": (1, 2.5)},
        "none": None,
    }


def test_checkpoint_round_trips_arrays_bit_for_bit_and_meta_floats_exactly(tmp_path, rng):
    arrays, meta = _arrays(rng), _meta()
    path = mio.save_checkpoint(mio.checkpoint_path(tmp_path, 1234), arrays, meta)
    assert path.name == "checkpoint_00001234.npz"
    back, meta_back = mio.load_checkpoint(path)

    assert sorted(back) == sorted(arrays)
    for name, a in arrays.items():
        assert back[name].dtype == a.dtype and back[name].shape == a.shape, name
        assert back[name].tobytes() == a.tobytes(), name
    assert meta_back["t"] == 0.1 + 0.2 and meta_back["t"].hex() == (0.1 + 0.2).hex()
    assert meta_back["dt"] == 1.0 / 3.0
    assert meta_back["step"] == 1234 and type(meta_back["step"]) is int
    assert meta_back["done"] is False
    assert meta_back["tiny"] == 5e-324
    assert math.isnan(meta_back["nan"]) and meta_back["inf"] == -math.inf
    assert meta_back["nested"] == {"h": [0.01, 0.02], "tuple": [1, 2.5]}
    assert meta_back["none"] is None and meta_back["scheme"] == "symplectic"
    assert _leftovers(tmp_path) == []


def test_checkpoint_never_pickles_and_rejects_object_arrays(tmp_path, rng):
    path = mio.save_checkpoint(tmp_path / "c.npz", _arrays(rng), _meta())
    with np.load(path, allow_pickle=False) as npz:  # readable without pickle
        header = json.loads(npz["__meta__"].tobytes())
    assert header["format"] == "mlsgalerkin-checkpoint" and header["version"] == 1

    with pytest.raises(ValueError, match="pickle"):
        mio.save_checkpoint(tmp_path / "o.npz", {"o": np.array([1, "a", None], dtype=object)}, {})
    assert not (tmp_path / "o.npz").exists()


@pytest.mark.parametrize(
    ("arrays", "meta", "match"),
    [
        ({}, {"f": object()}, r"meta\['f'\].*not JSON-serialisable"),
        ({}, {"deep": {"a": [1, {2}]}}, r"meta\['deep'\]\['a'\]\[1\]"),
        ({}, {"arr": np.zeros(3)}, "numpy array"),
        ({}, {1: "x"}, "keys must be str"),
        ({"__meta__": np.zeros(1)}, {}, "reserved"),
        ({"a/b": np.zeros(1)}, {}, "not allowed"),
    ],
)
def test_checkpoint_rejects_bad_input_with_a_clear_message(tmp_path, arrays, meta, match):
    with pytest.raises(ValueError, match=match):
        mio.save_checkpoint(tmp_path / "c.npz", arrays, meta)
    with pytest.raises(ValueError, match="must end in '.npz'"):
        mio.save_checkpoint(tmp_path / "c.dat", {}, {})


def test_truncated_or_corrupt_checkpoint_gives_a_clear_error(tmp_path, rng):
    good = mio.save_checkpoint(tmp_path / "good.npz", {"x": rng.random(2000)}, {"t": 1.0})
    raw = good.read_bytes()

    truncated = tmp_path / "truncated.npz"
    truncated.write_bytes(raw[: len(raw) // 2])
    with pytest.raises(mio.CheckpointError, match="truncated or corrupt"):
        mio.load_checkpoint(truncated)

    flipped = bytearray(raw)
    flipped[len(raw) // 2] ^= 0xFF  # inside the array data: caught by the zip CRC
    corrupt = tmp_path / "corrupt.npz"
    corrupt.write_bytes(bytes(flipped))
    with pytest.raises(mio.CheckpointError, match="truncated or corrupt"):
        mio.load_checkpoint(corrupt)

    garbage = tmp_path / "garbage.npz"
    garbage.write_bytes(b"not a zip at all")
    with pytest.raises(mio.CheckpointError):
        mio.load_checkpoint(garbage)

    with pytest.raises(FileNotFoundError, match="does not exist"):
        mio.load_checkpoint(tmp_path / "missing.npz")


def test_foreign_or_future_checkpoint_is_refused(tmp_path):
    plain = tmp_path / "plain.npz"
    np.savez(plain, x=np.zeros(3))
    with pytest.raises(mio.CheckpointError, match="not an mlsgalerkin checkpoint"):
        mio.load_checkpoint(plain)

    header = {"format": "mlsgalerkin-checkpoint", "version": 99, "arrays": [], "meta": {}}
    future = tmp_path / "future.npz"
    np.savez(future, __meta__=np.frombuffer(json.dumps(header).encode(), dtype=np.uint8))
    with pytest.raises(mio.CheckpointError, match="version 99"):
        mio.load_checkpoint(future)

    header["version"] = 1
    header["arrays"] = ["x"]  # listed but missing: a mismatched file
    odd = tmp_path / "odd.npz"
    np.savez(odd, __meta__=np.frombuffer(json.dumps(header).encode(), dtype=np.uint8))
    with pytest.raises(mio.CheckpointError, match="do not match"):
        mio.load_checkpoint(odd)


def test_failed_checkpoint_write_keeps_the_previous_checkpoint(tmp_path, monkeypatch):
    path = mio.checkpoint_path(tmp_path, 10)
    mio.save_checkpoint(path, {"x": np.arange(5.0)}, {"step": 10})

    def broken_savez(file, *args, **kwds):
        file.write(b"PK\x03\x04 partial zip")  # dies midway through the archive
        raise OSError("disk full")

    monkeypatch.setattr(ckpt.np, "savez", broken_savez)
    with pytest.raises(OSError, match="disk full"):
        mio.save_checkpoint(path, {"x": np.zeros(5)}, {"step": 11})
    monkeypatch.undo()

    arrays, meta = mio.load_checkpoint(path)
    np.testing.assert_array_equal(arrays["x"], np.arange(5.0))
    assert meta == {"step": 10}
    assert _leftovers(tmp_path) == []
    assert mio.latest_checkpoint(tmp_path) == path


def test_latest_and_prune_use_the_step_in_the_file_name(tmp_path):
    assert mio.latest_checkpoint(tmp_path) is None
    assert mio.latest_checkpoint(tmp_path / "missing") is None
    for step in (5, 100, 20, 123456789):
        mio.save_checkpoint(mio.checkpoint_path(tmp_path, step), {}, {"step": step})
    (tmp_path / ".checkpoint_999999999.npz.x1.tmp").write_bytes(b"")  # interrupted write
    (tmp_path / "checkpoint_final.npz").write_bytes(b"")  # not the naming scheme
    assert mio.latest_checkpoint(tmp_path) == tmp_path / "checkpoint_123456789.npz"

    removed = mio.prune_checkpoints(tmp_path, keep=2)
    assert [p.name for p in removed] == ["checkpoint_00000005.npz", "checkpoint_00000020.npz"]
    left = sorted(p.name for p in tmp_path.glob("checkpoint_*.npz"))
    assert left == ["checkpoint_00000100.npz", "checkpoint_123456789.npz", "checkpoint_final.npz"]
    assert mio.prune_checkpoints(tmp_path, keep=5) == []
    with pytest.raises(ValueError, match="keep"):
        mio.prune_checkpoints(tmp_path, keep=0)
    with pytest.raises(ValueError, match="non-negative"):
        mio.checkpoint_path(tmp_path, -1)


# ----------------------------------------------------------------------------------------
# time series
# ----------------------------------------------------------------------------------------


def test_timeseries_round_trip_is_exact(tmp_path):
    path = tmp_path / "sub" / "energy.csv"
    w = mio.TimeSeriesWriter(path, ["time", "step", "energy"])
    w.append({"time": 0.0, "step": 0, "energy": 0.1 + 0.2})
    w.append([np.float64(1e-300), np.int64(1), math.nan])
    w.append({"time": 2.0 / 3.0, "step": 2, "energy": None})
    w.append((math.inf, True, -0.0))
    w.flush()
    assert path.read_text().splitlines()[0] == "time,step,energy"
    assert w.rows[0] == {"time": 0.0, "step": 0, "energy": 0.1 + 0.2}

    data = mio.read_timeseries(path)
    assert list(data) == ["time", "step", "energy"]
    assert data["step"].dtype == np.int64
    np.testing.assert_array_equal(data["step"], [0, 1, 2, 1])
    assert data["time"].tolist() == [0.0, 1e-300, 2.0 / 3.0, math.inf]
    assert data["energy"][0] == 0.1 + 0.2
    assert math.isnan(data["energy"][1]) and math.isnan(data["energy"][2])
    assert math.copysign(1.0, data["energy"][3]) == -1.0
    assert _leftovers(path.parent) == []


def test_timeseries_resume_drops_rows_after_the_restart_time(tmp_path):
    path = tmp_path / "probe.csv"
    w = mio.TimeSeriesWriter(path, ["t", "p"])
    for k in range(6):
        w.append([0.1 * k, float(k)])
    w.flush()

    r = mio.TimeSeriesWriter.resume(path, after_time=0.1 * 2, time_column="t")
    assert [row["t"] for row in r.rows] == [0.0, 0.1, 0.2]
    r.append([0.25, 99.0])
    r.flush()
    assert mio.read_timeseries(path)["p"].tolist() == [0.0, 1.0, 2.0, 99.0]

    assert len(mio.TimeSeriesWriter.resume(path, None, time_column="t")) == 4
    fresh = mio.TimeSeriesWriter.resume(tmp_path / "new.csv", 1.0, columns=["time", "e"])
    assert fresh.columns == ["time", "e"] and fresh.rows == []
    with pytest.raises(FileNotFoundError):
        mio.TimeSeriesWriter.resume(tmp_path / "new.csv", 1.0)
    with pytest.raises(ValueError, match="no column 'time'"):
        mio.TimeSeriesWriter.resume(path, 1.0)
    with pytest.raises(ValueError, match="expected"):
        mio.TimeSeriesWriter.resume(path, 1.0, time_column="t", columns=["t", "q"])


def test_timeseries_rejects_bad_rows(tmp_path):
    w = mio.TimeSeriesWriter(tmp_path / "s.csv", ["time", "e"])
    with pytest.raises(ValueError, match="missing.*'e'.*unknown.*'E'"):
        w.append({"time": 0.0, "E": 1.0})
    with pytest.raises(ValueError, match="3 values but there are 2 columns"):
        w.append([0.0, 1.0, 2.0])
    with pytest.raises(ValueError, match="column 'e'.*only numbers"):
        w.append([0.0, "high"])
    with pytest.raises(ValueError, match="unique"):
        mio.TimeSeriesWriter(tmp_path / "s.csv", ["a", "a"])
    assert len(w) == 0


def test_failed_timeseries_flush_keeps_the_previous_file(tmp_path, monkeypatch):
    path = tmp_path / "s.csv"
    w = mio.TimeSeriesWriter(path, ["time"])
    w.append([0.0])
    w.flush()
    before = path.read_bytes()
    w.append([1.0])

    def broken_replace(src, dst):
        raise OSError("rename failed")

    monkeypatch.setattr(os, "replace", broken_replace)
    with pytest.raises(OSError, match="rename failed"):
        w.flush()
    monkeypatch.undo()
    assert path.read_bytes() == before
    assert _leftovers(tmp_path) == []


# ----------------------------------------------------------------------------------------
# imports
# ----------------------------------------------------------------------------------------


def test_importing_the_package_does_not_import_heavy_libraries():
    code = ("import sys, mlsgalerkin.io; "
            "print(sorted(m for m in ('meshio', 'pyvista', 'vtk', 'matplotlib') "
            "if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True)
    assert out.stdout.strip() == "[]"
