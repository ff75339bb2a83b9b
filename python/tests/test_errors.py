"""Bad input is hsnc.InputError (a ValueError), a failure while running
hsnc.RunError (a RuntimeError); each carries the message the command line
prints after "hsnc: " (for options, the library's message naming the field
where the command line names its flag)."""

import pytest

import hsnc
from conftest import model_path

BAD_MODEL = """
name = "bad"
[[mass]]
name = "m1"
m = -1
"""


def overflow_model(m, k):
    # Beyond double range (tests/test_extremes.cpp): k/m = 1e400 overflows
    # (refused when read); w = 1e150 rad/s switches every 2e-150 s (Zeno).
    return hsnc.Model.from_string("""
name = "ovf"
[[mass]]
name = "m1"
m = %s
[[spring]]
between = ["m1", "ground"]
k = %s
[[contact]]
between = ["m1", "ground"]
gap = 0
k = 12
[initial]
v = { m1 = 1.0 }
""" % (m, k), source="ovf.toml")


def cli_message(cli, tmp_path, text, *flags, code):
    path = tmp_path / "model.toml"
    path.write_text(text)
    p = cli("simulate", path, "--quiet", *flags, check=False)
    assert p.returncode == code and p.stdout == ""
    assert p.stderr.startswith("hsnc: ")
    return path, p.stderr[len("hsnc: "):].rstrip("\n")


def test_bad_model_text_is_input_error_with_the_cli_message(cli, tmp_path):
    path, message = cli_message(cli, tmp_path, BAD_MODEL, code=2)
    with pytest.raises(hsnc.InputError) as e:
        hsnc.Model.from_file(path)
    assert str(e.value) == message and "mass[1].m" in message
    assert isinstance(e.value, ValueError)
    with pytest.raises(ValueError) as e:
        hsnc.Model.from_string(BAD_MODEL, source=str(path))
    assert str(e.value) == message


def test_missing_file_and_unknown_override_are_input_errors(cli, tmp_path):
    missing = tmp_path / "none.toml"
    p = cli("simulate", missing, check=False)
    with pytest.raises(hsnc.InputError) as e:
        hsnc.Model.from_file(missing)
    assert p.returncode == 2 and "hsnc: " + str(e.value) == p.stderr.strip()
    p = cli("simulate", model_path("seed-scenario-2.toml"), "--set", "nope=1", check=False)
    with pytest.raises(hsnc.InputError) as e:
        hsnc.Model.from_file(model_path("seed-scenario-2.toml"), set={"nope": 1})
    assert p.returncode == 2 and "hsnc: " + str(e.value) == p.stderr.strip()


@pytest.mark.parametrize("kwargs, message", [
    ({"t_end": -1.0}, "hsnc::simulate(): t_end = -1: must be finite and after t0 = 0"),
    ({"t_end": 1.0, "dt": 0.0}, "hsnc::simulate(): dt = 0: must be > 0"),
    ({"t_end": 1.0, "method": "euler"}, "hsnc::method_from_name(): method = 'euler': expected hsnc, ab4, rk45 or cvode"),
    ({"t_end": 1.0, "method": "ab4"}, "hsnc::simulate(): integrator.h = nan: method ab4 needs a fixed step h > 0"),
    ({"t_end": 1.0, "kernels": "fast"},
     "hsnc::kernel_choice_from_name(): kernels = 'fast': expected auto, aot, generic, interp, eigen, jit or tiered"),
    ({"t_end": 1.0, "precision": "mp:5"}, "hsnc::precision_digits_from_name(): precision_digits = mp:5: "
                                          "expected double, or mp:N with N in 20..100"),
])
def test_bad_option_is_input_error_naming_the_field(kwargs, message):
    model = hsnc.Model.from_file(model_path("seed-scenario-2.toml"))
    with pytest.raises(hsnc.InputError) as e:
        hsnc.simulate(model, **kwargs)
    assert str(e.value) == message


def test_aot_kernels_for_an_edited_model_are_refused():
    model = hsnc.Model.from_file(model_path("seed-scenario-2.toml"), set={"F1": 100})
    with pytest.raises(hsnc.InputError, match=r"kernels = aot: no ahead-of-time kernels for model 'seed-scenario-2'"):
        hsnc.simulate(model, t_end=1, kernels="aot")


def test_failing_run_is_run_error():
    model = overflow_model("1", "1e300")
    with pytest.raises(hsnc.RunError) as e:
        hsnc.simulate(model, t_end=1)
    assert isinstance(e.value, RuntimeError)
    assert str(e.value).startswith("simulate: zeno: ")


def test_stiffness_over_mass_beyond_the_double_range_is_input_error():
    # k/m = 1e400 is refused when the model is read, naming the element.
    with pytest.raises(hsnc.InputError, match=r"key 'spring\[1\]\.k': .*natural frequency sqrt\(k/m\) would not be finite"):
        overflow_model("1e-200", "1e200")


def test_run_error_message_equals_the_cli(cli, tmp_path):
    text = """
name = "ovf"
[[mass]]
name = "m1"
m = 1
[[spring]]
between = ["m1", "ground"]
k = 1e300
[[contact]]
between = ["m1", "ground"]
gap = 0
k = 12
[initial]
v = { m1 = 1.0 }
"""
    path, message = cli_message(cli, tmp_path, text, "--t-end", "1", code=1)
    with pytest.raises(hsnc.RunError) as e:
        hsnc.simulate(hsnc.Model.from_file(path), t_end=1)
    assert str(e.value) == message and "1000 switches between t = " in message


def test_generate_into_a_file_is_run_error(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("not a directory")
    with pytest.raises(hsnc.RunError):
        hsnc.generate(hsnc.Model.from_file(model_path("bilinear-1dof.toml")), blocker)


def test_wrong_types_are_input_errors():
    with pytest.raises(hsnc.InputError, match="expected an hsnc.Model"):
        hsnc.simulate("models/seed-scenario-2.toml", t_end=1)
    model = hsnc.Model.from_file(model_path("bilinear-1dof.toml"))
    with pytest.raises(hsnc.InputError, match=r"t_end = 'soon': expected a finite number"):
        hsnc.simulate(model, t_end="soon")
    with pytest.raises(hsnc.InputError, match=r"max_events = -1"):
        hsnc.simulate(model, t_end=1, max_events=-1)
