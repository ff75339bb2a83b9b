#!/usr/bin/env python3
"""The paper's scenario 2 (models/seed-scenario-2.toml: stick-slip with a
contact) from Python: x1(t) and the phase portrait x1 against v1, with the
switch events marked. Usage: examples/scenario2.py [PNG] [T_END]
(default scenario2.png in the current directory, 60 s).

Needs `import hsnc` (./build.sh sets it up for Debian's python3) and
matplotlib (Debian python3-matplotlib)."""

import pathlib
import sys

import matplotlib

matplotlib.use("Agg")  # files only, no display
import matplotlib.pyplot as plt  # noqa: E402

import hsnc  # noqa: E402

MODEL = pathlib.Path(__file__).resolve().parents[1] / "models" / "seed-scenario-2.toml"
MARKERS = {"contact_close": ("^", "tab:red"), "contact_open": ("v", "tab:orange"), "stick": ("o", "black"),
           "release": ("o", "tab:green"), "reversal": ("D", "tab:purple")}


def main():
    png = sys.argv[1] if len(sys.argv) > 1 else "scenario2.png"
    t_end = float(sys.argv[2]) if len(sys.argv) > 2 else 60.0
    model = hsnc.Model.from_file(MODEL)
    r = hsnc.simulate(model, t_end=t_end, dt=0.002)
    s = r.summary
    print("%s: %s, t = %g s, %d samples, %d switch events (%s)" % (
        model.name, s["status"], s["t"], len(r.t), s["events"],
        ", ".join("%s %d" % kv for kv in s["counts"].items())))

    fig, (ax_t, ax_p) = plt.subplots(1, 2, figsize=(12, 4.8), gridspec_kw={"width_ratios": [1.6, 1]})
    ax_t.plot(r.t, r.x[:, 0], lw=0.8, color="tab:blue", label="x1")
    ax_p.plot(r.x[:, 0], r.v[:, 0], lw=0.5, color="tab:blue")
    # The switches involving m1 or the contact, at the exact switch state.
    for kind, (marker, colour) in MARKERS.items():
        e = r.events[(r.events.kind == kind) & ((r.events.element == "m1") | (kind.startswith("contact")))]
        if len(e):
            ax_t.plot(e.t, e.x[:, 0], marker, ms=3, color=colour, label="%s (%d)" % (kind.replace("_", " "), len(e)))
            ax_p.plot(e.x[:, 0], e.v[:, 0], marker, ms=3, color=colour)
    ax_t.set(xlabel="t [s]", ylabel="x1 [m]", title="%s: x1(t), %g s" % (model.name, t_end))
    ax_p.set(xlabel="x1 [m]", ylabel="v1 [m/s]", title="phase portrait of m1")
    ax_t.legend(loc="upper right", fontsize=7, ncol=2)
    for ax in (ax_t, ax_p):
        ax.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(png, dpi=90)
    print("wrote", png)


if __name__ == "__main__":
    main()
