"""The figures ``transient plot``, ``orders`` and ``loads`` write, drawn from real short runs and
checked for what a reader needs and a machine can check:

* every axes names its quantity with a unit in brackets (an x axis shared with the panel below
  takes that one's), a colour bar too;
* no two tick labels of an axis overlap, after drawing (their window extents);
* every legend lies off every axes (it hides no data), every title inside the figure;
* PNGs at 200 dpi;

and, figure by figure, the artists that carry its content against an independent computation:
the misfires marked at the firing TDC of the cycles ``[[gas.cylinders]]`` says misfire, each
cycle's band holding its samples' least and greatest speed, the indicator curves one per
distinct cylinder with the coinciding ones merged, the run-up figures only for a run-up, no bar
below its noise floor, the polar diagram's marks every 30° and its largest load.
"""
from __future__ import annotations

import math
import re
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
import pytest
from matplotlib.collections import PolyCollection, QuadMesh

import transient
from transient import plots
from transient.analysis.irregularity import cycle_boundaries
from transient.analysis.loads.crank_slider import loads_from_trajectory
from transient.analysis.loads.diagrams import articulated_diagrams, crank_slider_diagrams
from transient.analysis.orders import run_orders
from transient.cli import loads as cli_loads
from transient.cli import main
from transient.cli import orders as cli_orders
from transient.cli import plot as cli_plot
from transient.results import open_result

CASES = Path(__file__).resolve().parents[2] / "cases"
UNIT = re.compile(r"\[[^\]]+\]")
#: Axis labels that count rather than measure, and so have no unit.
COUNTS = {"cycle of the run"}


# ------------------------------------------------------------------------------------------------
# What every figure must satisfy


def _label_has_unit(ax, which):
    """The axes' x or y label has a unit; an x label may be left to the axes below that shares
    x with it, and an axis of named categories (bars per operating point) needs none."""
    text = (ax.get_xlabel() if which == "x" else ax.get_ylabel()).strip()
    if UNIT.search(text) or text in COUNTS:
        return True
    ticks = [t.get_text() for t in (ax.get_xticklabels() if which == "x" else
                                    ax.get_yticklabels()) if t.get_text()]
    if ticks and not any(re.fullmatch(r"[−\-+0-9.e]+", t) for t in ticks):
        return True
    if which == "x" and not text:
        return any(UNIT.search(o.get_xlabel()) or o.get_xlabel() in COUNTS
                   for o in ax.get_shared_x_axes().get_siblings(ax) if o is not ax)
    return False


def _drawn_ticklabels(axis):
    """The tick labels, major and minor, that ``axis`` draws: with text, at a tick inside its
    view."""
    lo, hi = sorted(axis.get_view_interval())
    slack = 1e-9 * (hi - lo)
    at = 0 if axis.axis_name == "x" else 1
    return [t for t in axis.get_ticklabels(which="both") if t.get_visible() and t.get_text()
            and lo - slack <= t.get_position()[at] <= hi + slack]


def _overlapping(boxes):
    for i, a in enumerate(boxes):
        for b in boxes[i + 1:]:
            if a.x0 < b.x1 - 1 and b.x0 < a.x1 - 1 and a.y0 < b.y1 - 1 and b.y0 < a.y1 - 1:
                return a, b
    return None


def check_readable(fig):
    """The checks every figure passes (module docstring)."""
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    figbox = fig.bbox
    data_axes = [ax for ax in fig.axes if ax.get_label() != "<colorbar>"]
    for ax in fig.axes:
        if ax.get_label() == "<colorbar>":
            assert UNIT.search(ax.get_ylabel() + ax.get_xlabel()), "colour bar without a unit"
            continue
        if ax.name == "polar":  # (the wear diagram: its radial tick labels carry kN)
            assert all("kN" in t.get_text() for t in ax.get_yticklabels() if t.get_text())
        else:
            assert _label_has_unit(ax, "y"), f"y label {ax.get_ylabel()!r}"
            assert _label_has_unit(ax, "x"), f"x label {ax.get_xlabel()!r}"
        for axis in (ax.xaxis, ax.yaxis):
            boxes = [t.get_window_extent(renderer) for t in _drawn_ticklabels(axis)]
            clash = _overlapping(boxes)
            assert clash is None, f"tick labels overlap: {clash}"
    legends = [ax.get_legend() for ax in fig.axes if ax.get_legend()] + list(fig.legends)
    for legend in legends:
        box = legend.get_window_extent(renderer)
        for ax in data_axes:
            area = ax.get_window_extent(renderer)
            assert not box.overlaps(area.shrunk(0.999, 0.999)), \
                f"legend {[t.get_text() for t in legend.get_texts()][:2]} lies on an axes"
    for text in [ax.title for ax in fig.axes] + list(fig.texts):
        if text.get_text():
            box = text.get_window_extent(renderer)
            assert (box.x0 >= figbox.x0 - 1 and box.x1 <= figbox.x1 + 1
                    and box.y0 >= figbox.y0 - 1 and box.y1 <= figbox.y1 + 1), \
                f"title {text.get_text()!r} clipped"


def _lines(ax):
    """The data lines of ``ax`` (no grid, axhline or axvline: those span the axes)."""
    return [a for a in ax.get_lines() if not _spans(a)]


def _spans(line):
    x, y = line.get_xdata(), line.get_ydata()
    return (len(x) == 2 and (np.ptp(np.asarray(x, float)) == 0 or np.ptp(np.asarray(y, float)) == 0)
            and line.get_transform() != line.axes.transData)


def _vlines(ax):
    return [a for a in ax.get_lines() if a.get_transform() != ax.transData
            and np.ptp(np.asarray(a.get_xdata(), float)) == 0]


# ------------------------------------------------------------------------------------------------
# Runs


def _run(tmp_path_factory, case, name, **tables):
    scene = transient.load_scene(CASES / case).replace(**tables)
    path = tmp_path_factory.mktemp(name) / f"{name}.h5"
    transient.simulate(scene, path)
    return open_result(path)


@pytest.fixture(scope="module")
def misfire(tmp_path_factory):
    """The misfire diesel for 50 revolutions (25 cycles, more than the cycle view's 20):
    cylinder 3 misfires in its cycles 10 and 20."""
    return _run(tmp_path_factory, "diesel_4cyl_misfire.toml", "misfire",
                run={"revolutions": 50})


@pytest.fixture(scope="module")
def spinup(tmp_path_factory):
    """The Gots spin-up for 60 revolutions: from 1000 rpm to its plateau, a run-up."""
    return _run(tmp_path_factory, "gots_diesel_spinup.toml", "spinup", run={"revolutions": 60})


@pytest.fixture(scope="module")
def load_steps(tmp_path_factory):
    """The Gots load steps, on at 0.5 s and off at 1.0 s, 1.5 s in all."""
    return _run(tmp_path_factory, "gots_diesel_load_steps.toml", "steps", run={"t_end": 1.5},
                load={"schedule_time": [0.5, 0.5, 1.0, 1.0]})


@pytest.fixture(scope="module")
def v8(tmp_path_factory):
    return _run(tmp_path_factory, "v8_cross_plane.toml", "v8", run={"revolutions": 8})


def _figures(pairs):
    return dict(pairs)


def _close(figs):
    for fig in figs.values():
        plt.close(fig)


# ------------------------------------------------------------------------------------------------
# transient plot


def test_plot_figures_of_the_misfire_run(misfire):
    res, scene = misfire, misfire.scene()
    figs = _figures(cli_plot.figures(res))
    assert {"speed", "torques", "speed_cycle", "inertia", "cylinder_torques",
            "indicator"} <= set(figs)
    for fig in figs.values():
        check_readable(fig)

    # speed over the run: the cycle view, each cycle's band holding its samples' extremes
    a_w, a_e = figs["speed"].axes[:2]
    tr = res.trajectory
    bounds, _ = cycle_boundaries(tr["t"], tr["phi"], scene.mechanism.cycle, scene.initial.phi)
    assert bounds.size - 1 == 25 > plots.CYCLE_VIEW_FROM
    band = next(c for c in a_w.collections if isinstance(c, PolyCollection))
    verts = band.get_paths()[0].vertices
    rpm = 30.0 / math.pi
    for i in (0, 9, 24):
        inside = (tr["t"] >= bounds[i]) & (tr["t"] <= bounds[i + 1])
        ys = verts[(verts[:, 0] >= bounds[i]) & (verts[:, 0] <= bounds[i + 1]), 1]
        lo = min(tr["omega"][inside].min(), *np.interp(bounds[i:i + 2], tr["t"], tr["omega"]))
        hi = max(tr["omega"][inside].max(), *np.interp(bounds[i:i + 2], tr["t"], tr["omega"]))
        assert ys.min() <= lo * rpm * (1 + 1e-12) and ys.max() >= hi * rpm * (1 - 1e-12)
    mean = next(line for line in a_w.get_lines() if line.get_label() == "cycle mean")
    np.testing.assert_allclose(mean.get_ydata(), scene.mechanism.cycle / np.diff(bounds) * rpm,
                               rtol=1e-12)
    # the misfires: cylinder 3's cycles 10 and 20 (cycle 1 the one in progress at φ0 = 0, which
    # began at its gas-exchange TDC, 540° − 360° − 720°), marked at their firing TDC
    firing = [math.radians(540.0 + (n - 2) * 720.0) for n in (10, 20)]
    expected = np.interp(firing, tr["phi"], tr["t"])
    for ax in (a_w, a_e):
        np.testing.assert_allclose(sorted(v.get_xdata()[0] for v in _vlines(ax)), expected,
                                   rtol=1e-9)
    labels = [t.get_text() for t in a_w.get_legend().get_texts()]
    assert "misfire of cylinder 3 (2)" in labels
    _close(figs)


def test_indicator_diagram_names_the_misfire_and_merges_equal_cylinders(misfire):
    """Cylinder 3's cycle 20 misfires; in the same engine cycle cylinders 1 and 4 burn full fuel
    (one curve, both named), cylinder 2 at 80 %: three curves, each cylinder's its own style,
    and the misfire on the motored curve (its peak p_c = p_a·ε^n1)."""
    from transient.analysis.thermo import own_cycle_numbers, own_cycles

    res, scene = misfire, misfire.scene()
    starts = own_cycles(scene, res.trajectory, 3)
    index = int(np.flatnonzero(own_cycle_numbers(scene, 3, starts) == 20)[0]) - starts.size
    figs = _figures(cli_plot.figures(res, cycles=[index]))
    fig = figs["indicator"]
    check_readable(fig)
    a_phi, a_pv = fig.axes
    runs = [line for line in a_phi.get_lines() if line.get_label().startswith("cylinder")]
    labels = sorted(line.get_label() for line in runs)
    assert len(runs) == 3, labels
    assert any(re.fullmatch(r"cylinders 1, 4, cycle \d+", lab) for lab in labels), labels
    assert any(re.fullmatch(r"cylinder 2, cycle \d+, fuel 0\.8", lab) for lab in labels), labels
    assert "cylinder 3, cycle 20, misfire" in labels
    assert len({(line.get_color(), str(line.get_linestyle())) for line in runs}) == 3
    misfired = next(line for line in runs if "misfire" in line.get_label())
    g = scene.gas
    p_c = g.p_a * g.compression_ratio ** g.n1 / 1e6
    assert misfired.get_ydata().max() == pytest.approx(p_c, rel=2e-3)
    # p–V: the same curves on log axes, with plain-number ticks
    assert len([ln for ln in a_pv.get_lines() if ln.get_label().startswith("cylinder")]) == 3
    assert a_pv.get_xscale() == a_pv.get_yscale() == "log"
    for t in a_pv.get_xticklabels() + a_pv.get_yticklabels():
        assert "^" not in t.get_text() and "times" not in t.get_text(), t.get_text()
    _close(figs)


def test_plot_figures_of_the_load_steps(load_steps):
    res = load_steps
    figs = _figures(cli_plot.figures(res))
    assert {"speed", "response", "pairs", "budget"} <= set(figs)
    for fig in figs.values():
        check_readable(fig)
    a_w = figs["speed"].axes[0]
    np.testing.assert_allclose(sorted(v.get_xdata()[0] for v in _vlines(a_w)), [0.5, 1.0],
                               rtol=1e-9)
    labels = [t.get_text() for t in a_w.get_legend().get_texts()]
    assert "load step (2)" in labels
    # friction mode switches come every cycle: named with their rate, not drawn
    assert any(re.fullmatch(r"friction mode switch: [0-9.]+ per cycle \(not drawn\)", lab)
               for lab in labels), labels
    _close(figs)


def test_plot_figures_of_a_v8(v8):
    figs = _figures(cli_plot.figures(v8))
    for fig in figs.values():
        check_readable(fig)
    # eight cylinders' torques, each its own colour and dash
    curves = [ln for ln in figs["cylinder_torques"].axes[0].get_lines()
              if ln.get_label().startswith("cylinder")]
    assert len(curves) == 8
    assert len({(ln.get_color(), str(ln.get_linestyle())) for ln in curves}) == 8
    _close(figs)


def test_written_pngs_are_at_200_dpi(misfire, tmp_path, capsys):
    from PIL import Image

    assert main(["plot", str(misfire.path), "-o", str(tmp_path)]) == 0
    capsys.readouterr()
    with Image.open(tmp_path / "misfire_torques.png") as image:
        assert image.info["dpi"] == pytest.approx((200, 200), abs=0.5)
        assert image.size[0] >= 1600  # (9 in wide at 200 dpi, less what tight layout trims)


# ------------------------------------------------------------------------------------------------
# transient orders


def _orders(res, cylinder=1):
    scene = res.scene()
    cuts = res.events.get("breakpoint", {}).get("phi", np.zeros(0))
    return run_orders(scene, res.trajectory, 720, cuts=cuts, piston_cylinder=cylinder)


def test_orders_of_a_steady_run_are_drawn_cycle_by_cycle(misfire):
    res = misfire
    ro = _orders(res)
    figs = _figures(cli_orders.figures(res, ro, 12.0, 1))
    assert set(figs) == {"orders", "orders_cycles"}  # (no run-up figure: 1.8 % of speed)
    for fig in figs.values():
        check_readable(fig)
    axes = [ax for ax in figs["orders_cycles"].axes if ax.get_label() != "<colorbar>"]
    waterfall, tracks, speed = axes
    mesh = next(c for c in waterfall.collections if isinstance(c, QuadMesh))
    y = mesh.get_coordinates()[:, 0, 1]
    np.testing.assert_allclose(y, np.arange(ro.cycles + 1) + 0.5)
    # the misfires at the cycles they happened in: the engine cycle that holds each firing TDC
    tr = res.trajectory
    tb, _ = cycle_boundaries(tr["t"], tr["phi"], res.scene().mechanism.cycle, 0.0)
    times = np.interp([math.radians(540.0 + (n - 2) * 720.0) for n in (10, 20)], tr["phi"],
                      tr["t"])
    expected = np.searchsorted(tb, times, side="right")
    for ax in (tracks, speed):
        np.testing.assert_array_equal(sorted(v.get_xdata()[0] for v in _vlines(ax)), expected)
    _close(figs)


def test_piston_orders_draw_nothing_below_their_noise_floor(misfire):
    """W/W₁ of the same engine at constant ω̄ holds round-off (about 1e-16) at the orders a
    crank-slider does not have; no bar below each series' floor is drawn, and each floor is
    drawn."""
    res = misfire
    ro = _orders(res)
    figs = _figures(cli_orders.figures(res, ro, 12.0, 1))
    ax = figs["orders"].axes[-1]
    assert ax.get_yscale() == "log"
    floors = {line.get_label().split(":")[0]: line.get_ydata()[0] for line in ax.get_lines()
              if "rtol" in line.get_label() or "rounding" in line.get_label()}
    assert set(floors) == {"run", "constant ω̄"}
    assert floors["run"] == pytest.approx(cli_orders.RUN_FLOOR_RTOL * res.scene().solver.rtol)
    assert floors["constant ω̄"] == pytest.approx(720 * np.finfo(float).eps)
    rel = ro.piston.relative_constant[-1]
    assert np.any((rel > 0) & (rel < 1e-14))  # (what the floor keeps out)
    containers = list(ax.containers)
    for container, floor in zip(containers, (floors["run"], floors["constant ω̄"])):
        heights = [bar.get_height() for bar in container]
        assert heights and min(heights) >= floor
    # the bars drawn are the orders above the floor, each its amplitude
    kept = (ro.orders > 0) & (ro.orders <= 12.0 + 1e-9) & (rel >= floors["constant ω̄"])
    np.testing.assert_allclose([bar.get_height() for bar in containers[1]], rel[kept])
    _close(figs)


def test_orders_of_a_run_up(spinup):
    res = spinup
    ro = _orders(res)
    figs = _figures(cli_orders.figures(res, ro, 12.0, 1))
    assert set(figs) == {"orders", "orders_runup"}
    for fig in figs.values():
        check_readable(fig)
    waterfall, campbell, tracks = [ax for ax in figs["orders_runup"].axes
                                   if ax.get_label() != "<colorbar>"]
    mesh = next(c for c in waterfall.collections if isinstance(c, QuadMesh))
    y = mesh.get_coordinates()[:, 0, 1]
    assert np.all(np.diff(y) >= 0)  # a speed axis
    assert y[0] <= ro.omega_mean.min() * 30 / math.pi <= y[-1]
    for line in _lines(tracks):
        if line.get_label().startswith("order"):
            assert np.all(np.diff(line.get_xdata()) >= 0)  # joined in the order of speed
    _close(figs)


def test_orders_cli_writes_the_figure_its_run_calls_for(misfire, spinup, tmp_path, capsys):
    for res, kind in ((misfire, "cycles"), (spinup, "runup")):
        out = tmp_path / kind
        assert main(["orders", str(res.path), "-o", str(out)]) == 0
        names = {p.name for p in out.iterdir()}
        stem = res.path.stem
        assert f"{stem}_orders_{kind}.png" in names
        other = "runup" if kind == "cycles" else "cycles"
        assert f"{stem}_orders_{other}.png" not in names
    capsys.readouterr()


def test_orders_of_an_elastic_run_up_draw_the_line(tmp_path_factory):
    """An elastic run-up (the six from 2300 rpm, 30 revolutions): the Campbell diagram with the
    run's orders, a marker per cycle and order at (n, q·n/60), the order labels outside the
    axes, clear of its legend; the line cycle by cycle against the cycle-mean speed: the
    elements' torques, the column's six strongest orders, the damping's power with the dampers
    apart and the sections summed."""
    import argparse

    from transient.cli import line_orders

    res = _run(tmp_path_factory, "inline6_damper.toml", "six", initial={"omega_rpm": 2300},
               run={"revolutions": 30})
    args = argparse.Namespace(line_column=None, samples_per_cycle=720, max_order=12.0,
                              detrend="auto")
    r = line_orders.report(res, res.scene(), args, res.events["breakpoint"]["phi"])
    figs = _figures(line_orders.figures(r))
    assert set(figs) == {"campbell", "cycles_figure"}
    for fig in figs.values():
        check_readable(fig)
    campbell = figs["campbell"].axes[0]
    dots = campbell.collections[-1].get_offsets()
    rpm = r.rpm
    assert np.all((dots[:, 0] >= rpm.min() - 1e-9) & (dots[:, 0] <= rpm.max() + 1e-9))
    ratio = dots[:, 1] / dots[:, 0] * 60.0  # each marker on its order's line
    assert np.allclose(ratio, np.round(2 * ratio) / 2, atol=1e-9)
    fig = figs["campbell"]
    renderer = fig.canvas.get_renderer()
    labels = [t for t in campbell.texts if re.fullmatch(r"[0-9.]+", t.get_text())]
    assert len(labels) == 24
    spine = campbell.get_window_extent(renderer)
    legend = campbell.get_legend().get_window_extent(renderer)
    for t in labels:
        box = t.get_window_extent(renderer)
        assert box.x0 >= spine.x1 and box.x1 <= legend.x0
    torque, tracks, power = [ax for ax in figs["cycles_figure"].axes
                             if ax.get_label() != "<colorbar>"]
    assert torque.get_xlabel() == tracks.get_xlabel() == ""
    assert power.get_xlabel() == "cycle-mean speed [rpm]"
    assert len(_lines(tracks)) == 6 and tracks.get_yscale() == "log"
    assert [line.get_label() for line in _lines(power)] == [
        "damper silicone at pulley", "sections, all", "absolute damping, all stations"]
    _close(figs)


# ------------------------------------------------------------------------------------------------
# transient loads


def test_load_figures_of_the_misfire_run(misfire):
    res, scene = misfire, misfire.scene()
    d = crank_slider_diagrams(scene, res.trajectory, 1)
    figs = _figures(cli_loads.crank_slider_figures(scene, d))
    assert set(figs) == {"loads_polar", "loads_crankpin", "loads_wear", "loads_running_torques"}
    for fig in figs.values():
        check_readable(fig)
    crankpin, journal = figs["loads_polar"].axes
    for ax in (crankpin, journal):
        dots = next(ln for ln in ax.get_lines() if ln.get_label() == "every 30° of crank angle")
        assert len(dots.get_xdata()) == 24  # 720° / 30°
        stars = [ln for ln in ax.get_lines() if "TDC" in ln.get_label()]
        assert {ln.get_label().split(" (")[0] for ln in stars} == {"firing TDC",
                                                                  "gas-exchange TDC"}
    # cylinder 1's firing TDC at 360° of the cycle (firing_deg 360, no offset), where its
    # crankpin load is what the loads give there
    star = next(ln for ln in crankpin.get_lines() if ln.get_label().startswith("firing TDC"))
    assert star.get_label() == "firing TDC (360°)"
    loads = loads_from_trajectory(scene, d.window.columns)
    at = np.interp(360.0, d.window.angle_deg, loads.R_T[0]) / 1e3
    assert star.get_xdata()[0] == pytest.approx(at, rel=1e-9, abs=1e-9)
    # the largest load, in the title, against the loads' own magnitude
    m = re.search(r"largest: ([0-9.]+) kN at ([0-9]+)°", crankpin.get_title())
    k = int(np.argmax(loads.R[0]))
    assert float(m.group(1)) == pytest.approx(loads.R[0][k] / 1e3, rel=2e-3)
    assert int(m.group(2)) == round(d.window.angle_deg[k])
    # the wear diagram: a polar axis whose rim is zero load, the rays' cycle-mean loads in kN
    wear = figs["loads_wear"].axes[0]
    assert wear.name == "polar"
    lo, hi = wear.get_ylim()
    assert hi == 0.0 and lo > 0.0
    rays, sums = d.crankpin_wear
    line = wear.get_lines()[0]
    np.testing.assert_allclose(line.get_ydata()[:-1], sums / d.wear_weight / 1e3, rtol=1e-12)
    assert d.wear_weight == pytest.approx(d.window.samples - 1, rel=1e-12)
    _close(figs)


def test_load_figures_of_a_radial_engine(tmp_path_factory):
    res = _run(tmp_path_factory, "radial_5cyl.toml", "radial", run={"revolutions": 6})
    scene = res.scene()
    d = articulated_diagrams(scene, res.trajectory)
    figs = _figures(cli_loads.articulated_figures(scene, d))
    for fig in figs.values():
        check_readable(fig)
    (ax,) = figs["loads_polar"].axes
    assert "largest:" in ax.get_title()
    assert any(ln.get_label().startswith("firing TDC") for ln in ax.get_lines())
    _close(figs)


def test_the_checks_catch_what_they_are_for():
    """Each check fails on a figure with the fault it looks for: a legend on the data, tick
    labels run into each other (the default log formatter on a narrow axes), a title wider than
    the figure, an axis without a unit."""
    faults = []
    fig, ax = plt.subplots(figsize=(4, 3))
    ax.plot([0, 1], [0, 1], label="a")
    ax.set(xlabel="x [m]", ylabel="y [m]")
    ax.legend(loc="center")
    faults.append(fig)
    fig, ax = plt.subplots(figsize=(2.5, 3))
    ax.loglog([0.031, 0.62], [0.1, 10])
    ax.set(xlabel="V [dm³]", ylabel="p [MPa]")
    faults.append(fig)
    fig, ax = plt.subplots(figsize=(3, 3))
    ax.plot([0, 1], [0, 1])
    ax.set(xlabel="x [m]", ylabel="y [m]", title="a title far wider than the figure it is on")
    faults.append(fig)
    fig, ax = plt.subplots(figsize=(3, 3))
    ax.plot([0, 1], [0, 1])
    ax.set(xlabel="x", ylabel="y [m]")
    faults.append(fig)
    for fig in faults:
        with pytest.raises(AssertionError):
            check_readable(fig)
        plt.close(fig)
