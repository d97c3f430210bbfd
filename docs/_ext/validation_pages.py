"""The Validation page's tables and figures, generated from the tests' own references.

``tests/references`` holds every comparison the suite makes with a published table, a printed
formula, an independent computation or a closed form: the reference value with its source and
misprints, the tolerance with its reason, and a case that runs the model for the computed side.
The tests assert those comparisons; this extension runs the same cases during the build and
renders them, so the page shows what the tests assert and no number on it is typed by hand.

* ``validation-table``: one table of the cases listed in its body (``module.case`` per line):
  per comparison the quantity, the source and kind of the reference value, the reference and
  the model at the decisive row, the deviation, what is allowed and why, and the test.
* ``validation-figure``: a figure drawn from the same cases (``FIGURES``), written to
  ``docs/_generated/validation`` at twice the screen resolution.

A comparison that fails is a build warning (an error under ``-W``), and so is a case of
``tests/references`` that no table shows.
"""
from __future__ import annotations

import functools
import math
import sys
from pathlib import Path

import numpy as np
from docutils import nodes
from docutils.parsers.rst import directives
from sphinx.util import logging
from sphinx.util.docutils import SphinxDirective

ROOT = Path(__file__).resolve().parents[2]
if str(ROOT / "tests") not in sys.path:
    sys.path.insert(0, str(ROOT / "tests"))

from references import load_all  # noqa: E402

logger = logging.getLogger(__name__)
OUT = Path("_generated") / "validation"
SUPERSCRIPT = str.maketrans("-0123456789", "⁻⁰¹²³⁴⁵⁶⁷⁸⁹")
KIND_TEXT = {"printed": "printed", "formula": "formula evaluated", "independent": "independent"}


@functools.cache
def comparisons(name: str):
    cases = load_all()
    if name not in cases:
        raise KeyError(f"no case {name!r} in tests/references (known: {', '.join(cases)})")
    return cases[name]()


# ------------------------------------------------------------------------------------------------
# Numbers


def power(x: float, sig: int = 2) -> str:
    """A positive x as a·10ⁿ below 0.01 and above 10⁵, plainly between: 2·10⁻³, 1.5·10⁻¹¹,
    0.05, 829."""
    if x == 0:
        return "0"
    mantissa, e = f"{x:.{sig - 1}e}".split("e")
    e = int(e)
    if -2 <= e <= 4:
        return np.format_float_positional(float(f"{x:.{sig}g}"), trim="-")
    mantissa = mantissa.rstrip("0").rstrip(".")
    return ("" if mantissa == "1" else mantissa + "·") + "10" + str(e).translate(SUPERSCRIPT)


def digits(c) -> int:
    """Significant digits to show the comparison's numbers with: enough to read a deviation of
    the size allowed, at most 8."""
    t = c.tolerance
    x = float(np.max(np.abs(np.atleast_1d(np.asarray(c.computed, float))))) or 1.0
    if t.abs is not None:
        need = math.log10(x / t.abs)
    elif t.rel is not None:
        need = -math.log10(t.rel)
    else:
        return 4
    return min(max(math.ceil(need) + 2, 3), 8)


def number(x: float, sig: int) -> str:
    """x to ``sig`` significant digits; as a·10ⁿ when it is tiny or huge."""
    if x != 0 and not 1e-3 <= abs(x) < 1e7:
        return ("−" if x < 0 else "") + power(abs(x), min(sig, 4))
    return f"{x:.{sig}g}".replace("-", "−")


def reference(x: float, c) -> str:
    """A printed value as given; a formula's or an independent value like the model's."""
    return number(x, 6) if c.kind == "printed" else number(x, digits(c))


def allowed(c) -> str:
    t, unit = c.tolerance, f" {c.unit}" if c.unit else ""
    if t.abs is not None:
        return f"≤ {power(t.abs)}{unit}"
    if t.rel is not None:
        return f"≤ {power(t.rel)} relative"
    if t.low is not None and t.high is not None:
        return f"within {number(t.low, 6)} … {number(t.high, 6)}{unit}"
    if t.low is not None:
        return f"≥ {number(t.low, 6)}{unit}"
    return f"≤ {power(t.high)}{unit}"


def deviation(c) -> str:
    """The deviation against what is allowed: "9.9·10⁻⁴ ≤ 2·10⁻³ MPa"; a bound alone."""
    if not c.tolerance.on_deviation:
        return allowed(c)
    return f"{power(c.statistic)} {allowed(c)}"


# ------------------------------------------------------------------------------------------------
# The table


def _para(*parts, classes=()):
    p = nodes.paragraph(classes=list(classes))
    for part in parts:
        p += part if isinstance(part, nodes.Node) else nodes.Text(part)
    return p


def _small(text: str):
    return nodes.inline(text=text, classes=["validation-small"])


def _entry(*paragraphs, morerows: int = 0):
    e = nodes.entry(morerows=morerows) if morerows else nodes.entry()
    for p in paragraphs:
        e += p
    return e


def _row(c, why: int, test_entry=None):
    """One comparison: quantity, source, reference → model at the decisive row, deviation
    against what is allowed (with the number of its reason under the table), test."""
    row = nodes.row(classes=[] if c.holds else ["validation-failed"])
    quantity = [_para(c.quantity)]
    if c.note:
        quantity.append(_para(_small(c.note)))
    row += _entry(*quantity)
    row += _entry(_para(c.source), _para(_small(KIND_TEXT[c.kind])))
    i, unit = c.worst, f" {c.unit}" if c.unit else ""
    computed = np.atleast_1d(np.asarray(c.computed, float))
    model = number(computed[i], digits(c))
    if c.reference is None:
        pair = [_para(f"model {model}{unit}")]
    else:
        pair = [_para(f"{reference(np.atleast_1d(c.reference)[i], c)} → {model}{unit}")]
    if computed.size > 1 and c.at is not None:
        pair.append(_para(_small(f"worst of {computed.size}, at {c.at_name.split(' [')[0]} "
                                 f"= {c.at[i]:g}{'°' if '°' in c.at_name else ''}")))
    row += _entry(*pair)
    mark = nodes.inline(text="✓ " if c.holds else "✗ ",
                        classes=["validation-ok" if c.holds else "validation-bad"])
    row += _entry(_para(mark, deviation(c), " ", _small(f"[{why}]")))
    if test_entry is not None:
        row += test_entry
    return row


HEADERS = ("Quantity", "Reference from", "Reference → model", "Deviation, allowed", "Test")
WIDTHS = (23, 19, 20, 18, 20)


class ValidationTable(SphinxDirective):
    """A table of the comparisons of the cases named in the body, one per line, and below it
    the reasons for the tolerances, numbered."""

    has_content = True
    option_spec = {"caption": directives.unchanged}

    def run(self):
        names = [line.strip() for line in self.content if line.strip()]
        table = nodes.table(classes=["validation-table", "colwidths-given"])
        if "caption" in self.options:
            table += nodes.title(text=self.options["caption"])
        group = nodes.tgroup(cols=len(HEADERS))
        table += group
        for w in WIDTHS:
            group += nodes.colspec(colwidth=w)
        head = nodes.thead()
        row = nodes.row()
        for h in HEADERS:
            row += _entry(_para(h))
        head += row
        group += head
        body = nodes.tbody()
        group += body
        reasons: list[str] = []
        for name in names:
            try:
                cs = comparisons(name)
            except Exception as exc:  # a case that cannot run is a broken page
                logger.warning(f"validation case {name}: {exc}", location=self.get_location())
                continue
            self.env.validation_shown = getattr(self.env, "validation_shown", set()) | {name}
            path, _, function = cs[0].test.partition("::")
            test = _entry(_para(nodes.literal(text=function)), _para(_small(f"tests/{path}")),
                          morerows=len(cs) - 1)
            for k, c in enumerate(cs):
                if not c.holds:
                    logger.warning(f"validation: {c.failure} [{name}]",
                                   location=self.get_location())
                if c.tolerance.why not in reasons:
                    reasons.append(c.tolerance.why)
                body += _row(c, reasons.index(c.tolerance.why) + 1, test if k == 0 else None)
        notes = nodes.enumerated_list(enumtype="arabic", classes=["validation-reasons"])
        for why in reasons:
            notes += nodes.list_item("", _para(why))
        return [table, _para(_small("Why that much is allowed, by the number in brackets:"),
                             classes=["validation-why"]), notes]


# ------------------------------------------------------------------------------------------------
# Figures


def _save(fig, srcdir: Path, name: str) -> str:
    out = srcdir / OUT
    out.mkdir(parents=True, exist_ok=True)
    fig.savefig(out / f"{name}.png", dpi=200, bbox_inches="tight")
    import matplotlib.pyplot as plt

    plt.close(fig)
    return "/" + (OUT / f"{name}.png").as_posix()


def figure_gots_forces():
    """П4.1 N, S, K, T of cylinder 1: printed, model (the book's inertia), misprinted cells."""
    import matplotlib.pyplot as plt
    from references import gots

    by = {c.quantity: c for c in comparisons("gots.p41_forces")}
    _, mech, ld, _, _ = gots.loads_as_printed()
    t = gots.p41()
    phi = t["phi_deg"]
    fig, axes = plt.subplots(2, 2, figsize=(8, 5.6), sharex=True, layout="constrained")
    for ax, name in zip(axes.flat, ("N", "S", "K", "T")):
        good, bad = by[f"{name}, cylinder 1"], by[f"{name}, misprinted cells"]
        model = np.empty(phi.size)
        model[np.isin(phi, good.at)] = good.computed
        model[np.isin(phi, bad.at)] = bad.computed
        ax.plot(phi, getattr(ld, name)[0] / mech.piston_area / gots.MPA, ":", color="0.5",
                lw=1, label="model, exact inertia")
        ax.plot(phi, model, ".-", color="C0", lw=1.2, ms=4, label="model, the book's inertia")
        ax.plot(good.at, good.reference, "o", mfc="none", color="C1", ms=6,
                label="П4.1 as printed")
        misprinted = t[f"{name}_MPa"][np.isin(phi, bad.at)]
        ax.plot(bad.at, misprinted, "x", color="C3", ms=8, mew=1.5, label="misprinted cell")
        ax.plot(bad.at, bad.reference, "D", mfc="none", color="C3", ms=5,
                label="its corrected value")
        ax.set_ylabel(f"{name} [MPa]")
        ax.grid(alpha=0.3)
    for ax in axes[1]:
        ax.set_xlabel("crank angle φ [°]")
        ax.set_xticks(np.arange(0, 721, 180))
    handles, labels = axes[0, 0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="outside lower center", ncols=5, frameon=False,
               fontsize="small")
    fig.suptitle("Gots, Table П4.1: forces on cylinder 1 per piston area, 4400 rpm\n"
                 "(φ = 0°: gas-exchange TDC, 360°: firing TDC)", fontsize="medium")
    return fig


def figure_gots_torques():
    """П4.2 engine torque (loads and the prescribed-speed run) and П4.4 running torques."""
    import matplotlib.pyplot as plt
    from matplotlib.legend_handler import HandlerTuple

    sums = {c.quantity: c for c in comparisons("gots.p42_torques")}
    run = comparisons("gots.p42_run")[0]
    running = {c.quantity: c for c in comparisons("gots.p44_p45_running_torques")}
    fig, (a, b) = plt.subplots(1, 2, figsize=(8, 3.8), layout="constrained")
    s = sums["engine torque ΣM"]
    a.plot(s.at, s.computed, "-", color="C0", label="model: loads analysis")
    a.plot(run.at, run.computed, "+", color="C2", ms=9, mew=1.5,
           label="model: prescribed-speed run")
    a.plot(s.at, s.reference, "o", mfc="none", color="C1", label="П4.2 as printed")
    a.set_title("engine torque ΣM, three cylinders")
    pairs = []
    for k, j in enumerate((2, 3, 4)):
        c = running[f"running torque, main journal {j}"]
        line, = b.plot(c.at, c.computed, "-", color=f"C{k}")
        dots, = b.plot(c.at, c.reference, "o", mfc="none", color=f"C{k}", ms=5)
        pairs.append(((line, dots), f"journal {j}"))
    b.set_title("running torques on main journals")
    for ax in (a, b):
        ax.set_xlabel("crank angle φ [°]")
        ax.set_ylabel("torque [N·m]")
        ax.set_xticks(np.arange(0, 721, 180))
        ax.grid(alpha=0.3)
    fig.legend(loc="outside lower left", fontsize="small", frameon=False,
               handles=a.get_lines(), labels=[ln.get_label() for ln in a.get_lines()])
    fig.legend([h for h, _ in pairs], [f"{lab}: model (line), П4.4 (circles)"
                                       for _, lab in pairs],
               handler_map={tuple: HandlerTuple(ndivide=None)}, loc="outside lower right",
               fontsize="small", frameon=False)
    return fig


def figure_gots_indicator():
    """П2.1: printed pressures and temperatures against the ideal mixed cycle."""
    import matplotlib.pyplot as plt
    from references import gots

    by = {c.quantity: c for c in comparisons("gots.p21_indicator")}
    t = gots.p21()
    mc = gots.cycle(gots.RHO_GEO)
    x = np.radians(np.linspace(180.0, 540.0, 2001))
    fig, (a, b) = plt.subplots(1, 2, figsize=(8, 3.6), layout="constrained")
    a.loglog(gots.volume(x) * 1e3, mc(x) / gots.MPA, "-", color="C0", lw=1.2,
             label="model: ideal mixed cycle, ρ = V(380°)/V_c")
    on = by["gas pressure, rows on the model's curves"]
    rows = np.isin(t["phi_deg"], on.at)
    a.loglog(t["volume_dm3"][~rows], t["pressure_MPa"][~rows], "o", mfc="none", color="0.55",
             ms=5, label="П2.1, rows off one curve (not asserted)")
    a.loglog(t["volume_dm3"][rows], t["pressure_MPa"][rows], "o", mfc="none", color="C1", ms=6,
             label="П2.1, rows on the model's curves")
    from matplotlib.ticker import NullFormatter

    a.set_xticks([0.04, 0.1, 0.2, 0.4], ["0.04", "0.1", "0.2", "0.4"])
    a.set_yticks([0.2, 0.5, 1, 2, 5, 10], ["0.2", "0.5", "1", "2", "5", "10"])
    for axis in (a.xaxis, a.yaxis):
        axis.set_minor_formatter(NullFormatter())
    a.set_xlabel("cylinder volume V [dm³]")
    a.set_ylabel("absolute pressure p [MPa]")
    a.set_title("indicator diagram, 180° to 540°")
    a.grid(alpha=0.3, which="both")
    a.legend(fontsize="small", loc="lower left")
    temp = by["gas temperature, T ∝ pV on the polytropes"]
    b.plot(temp.at, temp.computed, "-", color="C0", label="model: T ∝ pV")
    b.plot(temp.at, temp.reference, "o", mfc="none", color="C1", ms=5, label="П2.1 as printed")
    b.set_xlabel("crank angle φ [°] (360°: firing TDC)")
    b.set_ylabel("gas temperature T [K]")
    b.set_title("temperature along the cycle")
    b.grid(alpha=0.3)
    b.legend(fontsize="small", loc="upper right")
    return fig


def figure_gots_rod():
    """П3.2: the connecting rod's angular velocity and acceleration."""
    import matplotlib.pyplot as plt

    by = {c.quantity: c for c in comparisons("gots.p32_rod_kinematics")}
    fig, axes = plt.subplots(1, 2, figsize=(8, 3.1), layout="constrained")
    for ax, (q, label) in zip(axes, (("rod angular velocity ω_rod", r"$\omega_{rod}$ [1/s]"),
                                     ("rod angular acceleration ε_rod",
                                      r"$\varepsilon_{rod}$ [1/s²]"))):
        c = by[q]
        phi = np.linspace(0.0, 360.0, 721)
        ax.plot(c.at, c.computed, "-", color="C0", label="model: exact kinematics")
        ax.plot(c.at, c.reference, "o", mfc="none", color="C1", ms=5,
                label="П3.2, exact column")
        ax.set_xlabel("crank angle φ [°]")
        ax.set_ylabel(label)
        ax.set_xticks(np.arange(0, 361, 60))
        ax.set_xlim(phi[0], phi[-1])
        ax.grid(alpha=0.3)
        ax.legend(fontsize="small")
    fig.suptitle("Gots, Table П3.2: connecting rod at 460.53 rad/s, λ = 0.317",
                 fontsize="medium")
    return fig


def per_turn(t, phi, omega):
    """(time at each turn's end, mean, least and largest ω) of every whole turn of a run; the
    turns' ends interpolated in φ, which increases."""
    marks = phi[0] + 2 * np.pi * np.arange(int((phi[-1] - phi[0]) / (2 * np.pi)) + 1)
    t_marks = np.interp(marks, phi, t)
    idx = np.searchsorted(phi, marks)
    least = np.array([omega[i:j + 1].min() for i, j in zip(idx[:-1], idx[1:])])
    largest = np.array([omega[i:j + 1].max() for i, j in zip(idx[:-1], idx[1:])])
    return t_marks[1:], 2 * np.pi / np.diff(t_marks), least, largest


def figure_antonyuk():
    """The example's spin-up with one and four cylinders, turn by turn, and the last turn."""
    import matplotlib.pyplot as plt
    from references import antonyuk

    comparisons("antonyuk.four_cylinders_smoother")
    fig, (a, b) = plt.subplots(1, 2, figsize=(8, 3.6), layout="constrained")
    lo, hi = antonyuk.BAND
    for ax in (a, b):
        ax.axhspan(lo, hi, color="0.92", zorder=0, label="governor's droop band")
    for z, color in ((1, "C1"), (4, "C0")):
        _, tr = antonyuk.spin_up(z)
        label = f"{z} cylinder{'s' * (z > 1)}, δ = {antonyuk.last_turn_delta(z):.3g}"
        t_end, mean, least, largest = per_turn(tr["t"], tr["phi"], tr["omega"])
        a.fill_between(t_end, least, largest, step="pre", color=color, alpha=0.3, lw=0)
        a.step(t_end, mean, where="pre", color=color, lw=1.2, label=label + " (turn mean)")
        last = tr["phi"] >= tr["phi"][-1] - 2 * np.pi
        b.plot(np.degrees(tr["phi"][last] - tr["phi"][last][0]), tr["omega"][last], color=color,
               label=label)
    for ax in (a, b):
        ax.set_ylabel("shaft speed ω [rad/s]")
        ax.grid(alpha=0.3)
    a.set_xlabel("time t [s]")
    a.set_title("spin-up: each turn's mean and range")
    a.legend(fontsize="small", loc="lower right")
    b.set_xlabel("crank angle over the last turn [°]")
    b.set_xticks(np.arange(0, 361, 90))
    b.set_title(r"the last turn: $\delta = (\omega_{max} - \omega_{min})/\omega_{mean}$")
    b.set_ylim(44.0, 54.0)
    b.legend(fontsize="small", loc="upper right")
    return fig


def figure_semenov():
    """λᵢ against the bank angle, exact and by (61), with the printed points; the slave's
    acceleration at 180° against the master's."""
    import matplotlib.pyplot as plt
    from references import semenov

    from transient.mechanisms import articulated as art

    by = {c.quantity: c for c in comparisons("semenov.slave_dynamic_parameter")}
    banks = np.arange(0.0, 181.0, 5.0)
    exact, series = semenov.lambda_curves(banks)
    fig, (a, b) = plt.subplots(1, 2, figsize=(8, 3.6), layout="constrained")
    a.plot(banks, exact, "-", color="C0", label="model: exact second harmonic")
    a.plot(banks, series, "--", color="C2", label="Semenov (61), evaluated by the model")
    a.plot([0.0, 180.0], [by["λᵢ at δᵢ = 0° by (61)"].reference,
                          by["λᵢ at δᵢ = 180° by (61)"].reference], "o", mfc="none",
           color="C1", ms=8, label="printed: 0.304 at 0°, 0.686 at 180°")
    a.set_xlabel(r"bank angle $\delta_i$ of the slave cylinder [°]")
    a.set_ylabel(r"slave dynamic parameter $\lambda_i$ [–]")
    a.set_xticks(np.arange(0, 181, 30))
    a.set_title(r"second-harmonic amplitude of $W/(r\omega^2)$")
    a.grid(alpha=0.3)
    a.legend(fontsize="small")
    phi = np.linspace(0.0, 2 * np.pi, 721)
    W = art.axial_positions(semenov.radial([180]), phi)[2] / semenov.R
    b.plot(np.degrees(phi), W[:, 0], color="C0", label="master piston")
    b.plot(np.degrees(phi), W[:, 1], color="C3", label=r"slave at $\delta_i$ = 180°")
    ratio = by["largest slave acceleration at δᵢ = 180° over the master's"].computed
    b.set_title(f"constant ω: largest |W|, slave/master {ratio:.4f}")
    b.set_xlabel("crank angle φ [°]")
    b.set_ylabel(r"piston acceleration $W/(r\omega^2)$ [–]")
    b.set_xticks(np.arange(0, 361, 60))
    b.grid(alpha=0.3)
    b.legend(fontsize="small")
    return fig


def figure_overview():
    """Every comparison with a deviation: the deviation as a share of what is allowed."""
    import matplotlib.pyplot as plt

    names = sorted(load_all())
    groups = {"gots": "Gots", "antonyuk": "Antonyuk et al.", "semenov": "Semenov",
              "closed_forms": "closed forms"}
    fig, ax = plt.subplots(figsize=(8, 3.0), layout="constrained")
    for k, module in enumerate(groups):
        ratios = [c.ratio for n in names if n.startswith(module + ".")
                  for c in comparisons(n) if c.tolerance.on_deviation]
        ratios = np.maximum(np.array(ratios), 1e-12)
        y = k + np.linspace(-0.25, 0.25, ratios.size)
        ax.plot(ratios, y, "o", mfc="none", color=f"C{k}", ms=5)
        ax.text(2.0, k, f"{ratios.size}", va="center", fontsize="small")
    ax.axvline(1.0, color="C3", lw=1)
    ax.set_xscale("log")
    ax.set_xlim(1e-13, 10)
    ax.set_yticks(range(len(groups)), groups.values())
    ax.invert_yaxis()
    ax.set_xlabel("deviation over what is allowed [–] (left of the red line: holds; "
                  "exact zeros drawn at 10⁻¹²; right: how many)")
    ax.grid(alpha=0.3, axis="x")
    return fig


FIGURES = {"overview": figure_overview, "gots-forces": figure_gots_forces,
           "gots-torques": figure_gots_torques, "gots-indicator": figure_gots_indicator,
           "gots-rod": figure_gots_rod, "antonyuk-spinup": figure_antonyuk,
           "semenov-lambda": figure_semenov}


class ValidationFigure(SphinxDirective):
    """A figure of ``FIGURES``, with the body as its caption."""

    required_arguments = 1
    has_content = True
    option_spec = {"alt": directives.unchanged}

    def run(self):
        import matplotlib

        matplotlib.use("Agg")
        name = self.arguments[0]
        if name not in FIGURES:
            logger.warning(f"no validation figure {name!r} (known: {', '.join(FIGURES)})",
                           location=self.get_location())
            return []
        uri = _save(FIGURES[name](), Path(self.env.srcdir), name)
        figure = nodes.figure(classes=["validation-figure"])
        figure += nodes.image(uri=uri, alt=self.options.get("alt", name), width="100%")
        if self.content:
            parsed = nodes.container()
            self.state.nested_parse(self.content, self.content_offset, parsed)
            figure += nodes.caption("", "", *parsed[0].children)
        return [figure]


# ------------------------------------------------------------------------------------------------
# Every case on the page


def _merge(app, env, docnames, other):
    env.validation_shown = getattr(env, "validation_shown", set()) | getattr(
        other, "validation_shown", set())


def _check_complete(app, env):
    missing = sorted(set(load_all()) - getattr(env, "validation_shown", set()))
    if missing:
        logger.warning("validation cases of tests/references on no page: " + ", ".join(missing))


def setup(app):
    app.add_directive("validation-table", ValidationTable)
    app.add_directive("validation-figure", ValidationFigure)
    app.add_css_file("validation.css")
    app.connect("env-merge-info", _merge)
    app.connect("env-check-consistency", _check_complete)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
