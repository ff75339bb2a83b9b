"""Run by ctest (install.python) with PYTHONPATH=PREFIX/lib/python3/dist-packages
after `cmake --install BUILD --prefix PREFIX`: the installed module imports,
uses the installed libhsnc.so (and libhsnc_jit.so beside it) and equals the
installed `hsnc simulate`. Usage: check_installed.py PREFIX MODEL"""

import os
import subprocess
import sys

import numpy as np

prefix, model_file = os.path.realpath(sys.argv[1]), sys.argv[2]
import hsnc  # noqa: E402

assert os.path.realpath(hsnc.__file__).startswith(prefix + os.sep), hsnc.__file__
model = hsnc.Model.from_file(model_file)
aot = hsnc.simulate(model, t_end=2, dt=0.01)
jit = hsnc.simulate(model, t_end=2, dt=0.01, kernels="jit")
libs = {line.split()[-1] for line in open("/proc/self/maps") if "libhsnc" in line}
assert libs and all(lib.startswith(prefix + os.sep) for lib in libs), libs
assert (aot.summary["solver"], jit.summary["solver"]) == ("aot", "jit")
line = subprocess.run([os.path.join(prefix, "bin", "hsnc"), "simulate", model_file, "--t-end", "2", "--quiet"],
                      check=True, capture_output=True, text=True).stdout.split()
fields = dict(item.split("=", 1) for item in line)
for r in (aot, jit):
    assert r.summary["events"] == int(fields["events"])
    assert [r.summary["x"][m] for m in model.masses] == [float(fields["x_" + m]) for m in model.masses]
assert np.allclose(aot.x, jit.x, rtol=0, atol=1e-12)
print("installed hsnc: %s, libraries %s" % (hsnc.__file__, sorted(libs)))
