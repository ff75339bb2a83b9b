"""HDF5 results: the command line's --h5 file read back with h5py holds the
numbers of its CSV files bit for bit, with the model's text, the overrides,
the version and the command; hsnc.to_h5 writes the same datasets from Python."""

import csv

import h5py
import numpy as np
import pytest

import hsnc
from conftest import SOURCE_DIR, run_cli

HARDENING = str(SOURCE_DIR / "examples" / "hardening-stop.toml")
SCENARIO2 = str(SOURCE_DIR / "models" / "seed-scenario-2.toml")


def read_csv(path):
    with open(path, newline="") as f:
        rows = [r for r in csv.reader(f) if r and not r[0].startswith("#")]
    return rows[0], rows[1:]


def assert_table_is_csv(group, path):
    """Every CSV column is the group's dataset of that name, in the header's order; numbers bit for bit."""
    header, rows = read_csv(path)
    assert group.attrs["columns"] == ",".join(header)
    for i, name in enumerate(header):
        column = [r[i] for r in rows]
        data = group[name][:]
        assert len(data) == len(column), name
        if data.dtype.kind == "f":
            expected = np.array([float(c) if c else np.nan for c in column])
            np.testing.assert_array_equal(data, expected, err_msg=name)
        else:
            assert [d.decode() for d in data] == column, name


def assert_same_datasets(a, b, group):
    assert sorted(a[group]) == sorted(b[group]), group
    assert a[group].attrs["columns"] == b[group].attrs["columns"], group
    for name in a[group]:
        x, y = a[group][name][:], b[group][name][:]
        if x.dtype.kind == "f":
            np.testing.assert_array_equal(x, y, err_msg=group + "/" + name)
        else:
            assert list(x) == list(y), group + "/" + name


def test_simulate_h5_holds_the_csv_files_and_the_provenance(tmp_path):
    h5, out, events = tmp_path / "run.h5", tmp_path / "run.csv", tmp_path / "events.csv"
    run_cli("simulate", SCENARIO2, "--t-end", "20", "--set", "F1=200", "--out", out, "--events", events,
            "--h5", h5, "--section", "contact_close", "--quiet")
    with h5py.File(h5, "r") as f:
        assert f.attrs["format"] == "hsnc-h5 1"
        assert f.attrs["hsnc_version"] == hsnc.__version__
        assert "--set F1=200" in f.attrs["command"] and f.attrs["model_name"] == "seed-scenario-2"
        assert f["model/text"][()].decode() == open(SCENARIO2).read()
        assert [o.decode() for o in f["model/overrides"][:]] == ["--set F1=200"]
        assert_table_is_csv(f["simulate/trajectory"], out)
        assert_table_is_csv(f["simulate/events"], events)
        closes = f["simulate/events/kind"][:] == b"contact_close"
        np.testing.assert_array_equal(f["simulate/section/t"][:], f["simulate/events/t"][:][closes])
        assert f["simulate/summary/status"][0] == b"ok"


def test_sweep_periodic_lyapunov_h5_hold_their_csv_files(tmp_path):
    p = tmp_path
    run_cli("sweep", HARDENING, "--param", "omega", "--from", "0.6", "--to", "2", "--points", "9",
            "--continuation", "--out", p / "curve.csv", "--diagram", p / "diagram.csv", "--h5", p / "sweep.h5",
            "--quiet")
    run_cli("periodic", HARDENING, "--set", "omega=1.3", "--x0", "m=1.5", "--transient", "300", "--out",
            p / "orbit.csv", "--multipliers", p / "mu.csv", "--h5", p / "periodic.h5", "--quiet")
    run_cli("lyapunov", SCENARIO2, "--t-end", "30", "--out", p / "lyap.csv", "--h5", p / "lyap.h5", "--quiet")
    with h5py.File(p / "sweep.h5", "r") as f:
        assert_table_is_csv(f["sweep/curve"], p / "curve.csv")
        assert_table_is_csv(f["sweep/diagram"], p / "diagram.csv")
    with h5py.File(p / "periodic.h5", "r") as f:
        assert_table_is_csv(f["periodic/orbit"], p / "orbit.csv")
        assert_table_is_csv(f["periodic/multipliers"], p / "mu.csv")
        assert f["periodic/summary/stable"][0] == b"true"
    with h5py.File(p / "lyap.h5", "r") as f:
        assert_table_is_csv(f["lyapunov/convergence"], p / "lyap.csv")
        header, rows = read_csv(p / "lyap.csv")
        np.testing.assert_array_equal(f["lyapunov/exponents/lambda"][:], [float(c) for c in rows[-1][1:]])


def test_to_h5_writes_what_the_command_line_writes(tmp_path):
    p = tmp_path
    model = hsnc.Model.from_file(HARDENING, set={"omega": 1.3}, x0={"m": 1.5})
    run_cli("simulate", HARDENING, "--set", "omega=1.3", "--x0", "m=1.5", "--t-end", "50", "--h5", p / "cli.h5",
            "--quiet")
    hsnc.to_h5(hsnc.simulate(model, t_end=50), p / "py.h5", model)
    run_cli("periodic", HARDENING, "--set", "omega=1.3", "--x0", "m=1.5", "--transient", "300", "--h5",
            p / "cli-p.h5", "--quiet")
    hsnc.to_h5(hsnc.periodic(model, transient=300), p / "py-p.h5", model)
    base = hsnc.Model.from_file(HARDENING)
    run_cli("sweep", HARDENING, "--param", "omega", "--from", "0.6", "--to", "2", "--points", "9", "--harmonics",
            "2", "--h5", p / "cli-s.h5", "--quiet")
    hsnc.to_h5(hsnc.sweep(base, "omega", 0.6, 2.0, 9, harmonics=2), p / "py-s.h5", base)
    scenario = hsnc.Model.from_file(SCENARIO2)
    run_cli("lyapunov", SCENARIO2, "--t-end", "30", "--h5", p / "cli-l.h5", "--quiet")
    hsnc.to_h5(hsnc.lyapunov(scenario, t_end=30), p / "py-l.h5", scenario)
    pairs = [("", ["simulate/trajectory", "simulate/events", "simulate/summary"]),
             ("-p", ["periodic/orbit", "periodic/multipliers", "periodic/summary"]),
             ("-s", ["sweep/curve", "sweep/diagram"]), ("-l", ["lyapunov/convergence", "lyapunov/exponents"])]
    for suffix, groups in pairs:
        with h5py.File(p / ("cli%s.h5" % suffix), "r") as a, h5py.File(p / ("py%s.h5" % suffix), "r") as b:
            for g in groups:
                assert_same_datasets(a, b, g)
            assert a["model/text"][()] == b["model/text"][()]
            assert a.attrs["hsnc_version"] == b.attrs["hsnc_version"]


def test_h5_refuses_a_pipe_and_leaves_no_file_when_a_run_fails(tmp_path):
    r = run_cli("simulate", SCENARIO2, "--t-end", "1", "--h5", "/dev/null", check=False)
    assert r.returncode == 2 and "--h5 '/dev/null': HDF5 needs a regular file" in r.stderr
    target = tmp_path / "never.h5"
    r = run_cli("periodic", SCENARIO2, "--max-iterations", "1", "--h5", target, check=False)
    assert r.returncode == 1 and not target.exists()
    assert not list(tmp_path.iterdir())
    with pytest.raises(hsnc.InputError):
        hsnc.to_h5({"status": "ok"}, tmp_path / "x.h5", hsnc.Model.from_file(SCENARIO2))


def test_the_summary_tables_are_the_summary_lines(tmp_path):
    """simulate/summary and periodic/summary hold the stdout line's keys and values (periodic's
    `status` is the line's alone, its `events` the table's), a load step's count included; and
    hsnc.to_h5 writes the same simulate/summary."""
    load_step = str(SOURCE_DIR / "examples" / "load_step" / "sdnd106.toml")
    runs = [(("simulate", load_step, "--t-end", "2"), "simulate/summary", {"status", "method"}),
            (("simulate", HARDENING, "--t-end", "20"), "simulate/summary", {"status", "method"}),
            (("periodic", HARDENING, "--set", "omega=1.3", "--x0", "m=1.5", "--transient", "300"),
             "periodic/summary", {"stable"})]
    for k, (args, group, words) in enumerate(runs):
        h5 = tmp_path / ("run%d.h5" % k)
        line = run_cli(*args, "--h5", h5, "--quiet").stdout.split()
        values = dict(item.split("=", 1) for item in line)
        with h5py.File(h5, "r") as f:
            columns = f[group].attrs["columns"].split(",")
            expected = [key for key in values if not (group == "periodic/summary" and key == "status")]
            assert [c for c in columns if c != "events" or group == "simulate/summary"] == expected, args
            for key in expected:
                cell = f[group][key][0]
                if key in words:
                    assert cell.decode() == values[key], key
                else:
                    assert cell == float(values[key]), key
    with h5py.File(tmp_path / "run0.h5", "r") as f:
        assert "load_change" in f["simulate/summary"].attrs["columns"].split(",")
    model = hsnc.Model.from_file(load_step)
    hsnc.to_h5(hsnc.simulate(model, t_end=2), tmp_path / "py.h5", model)
    with h5py.File(tmp_path / "run0.h5", "r") as a, h5py.File(tmp_path / "py.h5", "r") as b:
        assert_same_datasets(a, b, "simulate/summary")
