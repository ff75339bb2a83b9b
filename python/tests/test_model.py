"""Models from files and strings: names, parameters, overrides; generate()."""

import math

import numpy as np

import hsnc
from conftest import TWO_MASS, model_path, read_csv, run_cli



def test_model_from_string_names_and_parameters():
    m = hsnc.Model.from_string(TWO_MASS)
    assert m.name == "pair" and m.description == "two masses, a contact and friction"
    assert m.masses == ["left", "right"] and m.contacts == ["stop"] and m.friction_masses == ["right"]
    assert m.dof == 2 and m.t0 == 0.0 and m.t_end == 4.0
    assert list(m.parameters) == ["g", "k", "kc"] and m.parameters["kc"] == 12.0
    assert np.array_equal(m.x0, [2.0, 0.0]) and np.array_equal(m.mass_values, [1.0, 2.0])
    # An override is seen by the parameters that use it.
    assert hsnc.Model.from_string(TWO_MASS, set={"k": 5}).parameters["kc"] == 15.0
    assert hsnc.Model.from_string(TWO_MASS, set={"k": "2 + 3"}).parameters["k"] == 5.0


def test_model_from_string_runs_as_its_file_does(tmp_path):
    path = tmp_path / "pair.toml"
    path.write_text(TWO_MASS)
    a = hsnc.simulate(hsnc.Model.from_string(TWO_MASS))  # t_end from [simulate]
    b = hsnc.simulate(hsnc.Model.from_file(path))
    assert a.summary["t"] == 4.0 and len(a.t) == 1001 and len(a.events) > 0
    assert np.array_equal(a.t, b.t) and np.array_equal(a.x, b.x) and np.array_equal(a.v, b.v)
    assert np.array_equal(a.events.t, b.events.t) and list(a.events.element) == list(b.events.element)
    assert set(a.events.element) <= {"stop", "left", "right"}


def test_override_keeps_exact_double():
    # 0.1 goes to the reader with 17 digits and comes back the same double.
    m = hsnc.Model.from_file(model_path("seed-scenario-2.toml"), x0={"m1": 0.1}, set={"F1": 1 / 3})
    assert m.x0[0] == 0.1 and m.parameters["F1"] == 1 / 3


def test_generate_writes_what_the_cli_writes(tmp_path):
    model = hsnc.Model.from_file(model_path("bilinear-1dof.toml"))
    names = hsnc.generate(model, tmp_path / "py")
    run_cli("generate", model_path("bilinear-1dof.toml"), "-o", tmp_path / "cli")
    cli_names = sorted(p.name for p in (tmp_path / "cli").iterdir())
    assert sorted(names) == cli_names and "registry.cpp" in names and "bilinear-1dof.manifest" in names
    for name in names:
        assert (tmp_path / "py" / name).read_bytes() == (tmp_path / "cli" / name).read_bytes()


def test_a_model_with_a_dashpot_runs_on_state_space_modes(tmp_path):
    """Non-proportional damping ([[damper]]) from Python: the bundled absorber
    runs as on the command line, on the interpreter and the reference
    (precision mp:N) as on the generic solver."""
    path = model_path("../examples/dashpot/absorber.toml")  # models/../examples
    r = hsnc.simulate(hsnc.Model.from_file(path), t_end=10.0)
    assert r.summary["status"] == "ok"
    cli = tmp_path / "events.csv"
    run_cli("simulate", path, "--t-end", "10", "--events", cli)
    rows = cli.read_text().splitlines()[1:]
    assert len(rows) == len(r.events) > 0
    assert [float(row.split(",")[0]) for row in rows] == list(r.events.t)
    interp = hsnc.simulate(hsnc.Model.from_file(path), t_end=10.0, kernels="interp")
    assert len(interp.events) == len(r.events)
    assert max(abs(a - b) for a, b in zip(interp.events.t, r.events.t)) < 1e-11
    ref = hsnc.simulate(hsnc.Model.from_file(path), t_end=10.0, precision="mp:30")
    assert len(ref.events) == len(r.events)
    assert max(abs(a - b) for a, b in zip(ref.events.t, r.events.t)) < 1e-11


def test_a_model_with_a_jenkins_element_gives_its_slider(tmp_path):
    """[[jenkins]] from Python: the bundled friction damper runs as on the
    command line, the events name the element, and the sliders come as
    Result.s (the CSV's s_<name> column) and events.s."""
    path = model_path("../examples/jenkins/friction_damper.toml")  # models/../examples
    model = hsnc.Model.from_file(path)
    assert model.jenkins == ["damper"]
    r = hsnc.simulate(model, t_end=5.0, dt=0.01)
    assert r.jenkins == ["damper"]
    assert r.s.shape == (len(r.t), 1)
    assert set(r.events.element) == {"damper"}
    assert set(r.events.kind) == {"release", "stick"}
    cli = tmp_path / "trajectory.csv"
    run_cli("simulate", path, "--t-end", "5", "--dt", "0.01", "--out", cli)
    lines = cli.read_text().splitlines()
    assert lines[0].endswith(",s_damper")
    assert [float(row.split(",")[-1]) for row in lines[1:]] == list(r.s[:, 0])
    assert r.summary["slider"]["damper"] == r.s[-1, 0]
    # At every event the damper's force k (x_platform - s) is at +-slip_force.
    force = 400.0 * (r.events.x[:, 1] - r.events.s[:, 0])
    assert max(abs(abs(force) - 5.0)) < 1e-12
    # The interpreted program runs it too (the kernels' closed form), and agrees.
    ri = hsnc.simulate(model, t_end=5.0, dt=0.01, kernels="interp")
    assert list(ri.events.kind) == list(r.events.kind)
    assert max(abs(ri.events.t - r.events.t)) < 1e-11
    assert max(abs(ri.s[:, 0] - r.s[:, 0])) < 1e-12
    # So does the CLN reference, its slider included.
    rr = hsnc.simulate(model, t_end=5.0, dt=0.01, precision="mp:30")
    assert list(rr.events.kind) == list(r.events.kind)
    assert max(abs(rr.events.t - r.events.t)) < 1e-12
    assert max(abs(rr.s[:, 0] - r.s[:, 0])) < 1e-12


def test_friction_between_two_bodies_runs_as_on_the_command_line(tmp_path):
    """[[friction]] between two bodies from Python: the bundled load on a
    shaking table gives the CLI's events, named by the element."""
    path = model_path("../examples/friction/stacked_blocks.toml")  # models/../examples
    r = hsnc.simulate(hsnc.Model.from_file(path), t_end=5.0)
    assert set(r.events.element) == {"interface"}
    assert list(r.events.kind[:2]) == ["release", "stick"]
    cli = tmp_path / "events.csv"
    run_cli("simulate", path, "--t-end", "5", "--events", cli)
    rows = cli.read_text().splitlines()[1:]
    assert [float(row.split(",")[0]) for row in rows] == list(r.events.t)


BOUNCING = """name = "bouncing"
[[mass]]
name = "m"
m = 2.0
[[spring]]
between = ["m", "ground"]
k = 8.0
[[contact]]
name = "stop"
between = ["m", "ground"]
gap = 0.5
restitution = 0.8
[initial]
v = { m = 3.0 }
[simulate]
t_end = 4.0
"""


def test_impacts_on_a_rigid_stop_run_from_python_as_from_the_cli(tmp_path):
    """restitution = e: the impacts of a spring-mass thrown at its stop, each
    leaving at -e times its speed in; Python gives the CLI's rows and counts."""
    r = hsnc.simulate(hsnc.Model.from_string(BOUNCING))
    assert set(r.events.kind) == {"impact"} and set(r.events.element) == {"stop"}
    w, d, speed = 2.0, 0.5, (9.0 - 4.0 * 0.25) ** 0.5
    assert abs(r.events.t[0] - math.asin(w * d / 3.0) / w) < 1e-14
    assert abs(r.events.v[0, 0] + 0.8 * speed) < 1e-14
    assert abs(r.events.v[1, 0] + 0.8 * 0.8 * speed) < 1e-13
    assert r.summary["counts"]["impact"] == len(r.events)
    assert "impact" not in hsnc.simulate(hsnc.Model.from_string(TWO_MASS)).summary["counts"]
    path = tmp_path / "bouncing.toml"
    path.write_text(BOUNCING)
    cli = tmp_path / "events.csv"
    out = run_cli("simulate", path, "--events", cli).stdout
    assert " impact=%d" % len(r.events) in out
    assert [float(row.split(",")[0]) for row in cli.read_text().splitlines()[1:]] == list(r.events.t)


def test_a_load_step_runs_from_python_as_from_the_cli(tmp_path):
    """[[load_step]]: the push on `right` switched off at t = 1; Python gives
    the CLI's rows, the step's among them, and counts it."""
    stepped = TWO_MASS.replace("[initial]", "[load]\nright = 0.5\n[[load_step]]\nname = \"off\"\nt = 1.0\n"
                               "load = { right = 0.0 }\n[initial]")
    r = hsnc.simulate(hsnc.Model.from_string(stepped))
    assert list(r.events.kind).count("load_change") == 1
    k = list(r.events.kind).index("load_change")
    assert r.events.t[k] == 1.0 and r.events.element[k] == "off"
    assert r.summary["counts"]["load_change"] == 1
    assert "load_change" not in hsnc.simulate(hsnc.Model.from_string(TWO_MASS)).summary["counts"]
    path = tmp_path / "stepped.toml"
    path.write_text(stepped)
    cli = tmp_path / "events.csv"
    out = run_cli("simulate", path, "--events", cli).stdout
    assert " load_change=1" in out
    rows = cli.read_text().splitlines()[1:]
    assert [float(row.split(",")[0]) for row in rows] == list(r.events.t)
    assert [row.split(",")[1] for row in rows] == list(r.events.kind)


def test_a_contact_along_a_direction_runs_from_python_as_from_the_file(tmp_path):
    # direction = { right = 2 } with gap and k scaled (u = 2 x, 2 gap, k / 4)
    # is the stop between right and ground: the same force, the same events.
    scaled = TWO_MASS.replace('between = ["right", "ground"]\ngap = 0.05\nk = "kc"',
                              'direction = { right = 2.0 }\ngap = 0.1\nk = "kc / 4"')
    assert scaled != TWO_MASS
    a = hsnc.simulate(hsnc.Model.from_string(TWO_MASS))
    b = hsnc.simulate(hsnc.Model.from_string(scaled))
    assert len(a.events) > 0
    assert np.array_equal(a.events.t, b.events.t) and list(a.events.element) == list(b.events.element)
    path = tmp_path / "scaled.toml"
    path.write_text(scaled)
    assert "stop  along 2 right  gap = 0.1" in run_cli("check", path).stdout


def test_a_reduced_structure_runs_from_python_as_from_the_cli(tmp_path):
    # A fixed-free chain of 30 masses, reduced to its end (stopped) and 4
    # fixed-interface modes: Python reads the same reduced model as the CLI
    # and runs the same events; its lowest frequency is the chain's closed form.
    n, m, k = 30, 0.01, 1.0e3
    M = "".join(f"{i} {i} {m}\n" for i in range(1, n + 1))
    K = "".join(f"{i} {i} {2 * k if i < n else k}\n" + (f"{i} {i - 1} {-k}\n" if i > 1 else "")
                for i in range(1, n + 1))
    (tmp_path / "M.mtx").write_text(f"%%MatrixMarket matrix coordinate real symmetric\n{n} {n} {n}\n" + M)
    (tmp_path / "K.mtx").write_text(f"%%MatrixMarket matrix coordinate real symmetric\n{n} {n} {2 * n - 1}\n" + K)
    dofs = ", ".join(f'"u{i}"' for i in range(1, n + 1))
    path = tmp_path / "chain.toml"
    path.write_text(f'name = "chain"\n[structure]\ndofs = [{dofs}]\nmass = "M.mtx"\nstiffness = "K.mtx"\n'
                    '[damping]\nalpha = 0.5\n[[forcing]]\nomega = 20.0\namplitude = { u30 = 1.0 }\n'
                    '[[contact]]\nname = "stop"\nbetween = ["u30", "ground"]\ngap = 0.002\nk = 5e3\n'
                    '[simulate]\nt_end = 2.0\n[reduction]\nmodes = 4\n')
    model = hsnc.Model.from_file(path)
    assert model.masses == ["u30", "q1", "q2", "q3", "q4"]
    result = hsnc.simulate(model)
    assert len(result.events) > 4
    events = tmp_path / "events.csv"
    run_cli("simulate", path, "--kernels", "interp", "--events", events)
    header, rows = read_csv(events)
    assert np.array_equal(result.events.t, np.array([float(r[header.index("t")]) for r in rows]))
    check = run_cli("check", path).stdout
    exact = 2 * np.sqrt(k / m) * np.sin(np.pi / (2 * (2 * n + 1)))
    line = next(l for l in check.splitlines() if l.startswith("    1  "))
    full, reduced = float(line.split()[1]), float(line.split()[2])
    assert abs(full - exact) < 1e-9 * exact
    assert exact * (1 - 1e-9) <= reduced < exact * (1 + 1e-3)  # above it (Rayleigh-Ritz), 1.6e-4 off with 4 modes
