"""Reading a scene: TOML text or a parsed dict → a validated :class:`~.records.Scene`.

:func:`transient.load_scene` parses the file; :func:`scene_from_dict` reads one table at a time
through a :class:`~.reader.Section` (the ``[mechanism]`` table by the class that
:data:`transient.mechanisms.MECHANISMS` names for its ``type``), then runs the checks across
tables (:mod:`.checks`). Every error is one :class:`~transient.errors.SceneError` naming the file
and the key as written.
"""
from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path
from typing import Any

from ..errors import SceneError
from ..forces.load_table import INTERPOLATIONS, SCHEDULE_MIN_GAP
from ..mechanisms import MECHANISMS, provides, reaction_joints
from ..units import ALL_SUFFIXES
from .budget import check_work
from .checks import check_analysis, check_consistency, check_gas_table, check_magnitudes
from .eta_map import check_map, grid_from_points
from .files import parse_toml, read_text, table_number, table_rows
from .reader import MISSING, Named, Section, finite_number, show_value
from .records import (
    DEFAULT_MAX_OUTPUT_BYTES,
    DEFAULT_MAX_STEPS,
    DETREND,
    ENVELOPE_RTOL,
    GOVERNOR_KEYS,
    MAX_COMBUSTION_OFFSET,
    MAX_CYLINDER_FACTOR,
    MAX_GAMMA,
    MAX_SAMPLES_PER_REV,
    METHODS,
    MIN_OUTPUT_DT,
    MIN_WIEBE_STEP,
    PAIR_MODELS,
    POLICIES,
    Analysis,
    Cylinder,
    Friction,
    Gas,
    Governor,
    Inertia,
    Initial,
    Load,
    LoadTable,
    Output,
    Pair,
    Run,
    Scene,
    Solver,
    Starter,
    Wiebe,
    Woschni,
)
from .shaft import read_shaft
from .write import to_toml


def load_scene(source: str | Path, *, text: str | None = None) -> Scene:
    """Read and validate a scene file (or TOML ``text``, with ``source`` naming it).

    Parameters
    ----------
    source : str or Path
        The scene file (TOML); the files a scene names (pressure tables, maps) are read relative
        to its folder.
    text : str, optional
        The scene as TOML, read instead of the file; ``source`` then only names it.

    Returns
    -------
    Scene
        The validated scene in SI units, every default filled in; its ``name`` is the file's
        stem unless ``[scene] name`` says otherwise.

    Raises
    ------
    transient.SceneError
        The file cannot be read or a key is wrong: one line naming the file, the key, what is
        wrong and what is allowed.

    Examples
    --------
    >>> import transient
    >>> scene = transient.load_scene("single.toml", text='''
    ... [mechanism]
    ... type = "crank-slider"
    ... crank_radius_mm = 47
    ... rod_length_mm = 148
    ... bore_mm = 88
    ... piston_mass = 1.52
    ... crank_mass = 0.912
    ... [mechanism.rod]
    ... model = "two-mass"
    ... mass = 1.752
    ... cg_from_pin_mm = 107.3
    ... [initial]
    ... omega_rpm = 1000
    ... [run]
    ... revolutions = 2
    ... ''')
    >>> scene.name
    'single'
    >>> scene.mechanism.crank_radius  # [m]: keys are read into SI
    0.047
    """
    path = Path(source)
    if text is None:
        text = read_text(path, "scene")
    scene = scene_from_dict(parse_toml(text, str(path)), file=str(path), base_dir=path.parent)
    return replace(scene, source_file=str(path), source_text=text)


class SweepNotScene(SceneError):
    """A sweep file (a ``[sweep]`` table and no ``[mechanism]``: :mod:`transient.sweeps.spec`)
    given where a scene is read; ``transient check`` checks it as a sweep instead."""

    def __init__(self, file: str) -> None:
        super().__init__("[sweep]", "this is a sweep file, not a scene: run it with `transient "
                                    "sweep`, check it with `transient check`", file=file)


def replace_scene(scene: Scene, /, **tables: dict) -> Scene:
    """A copy of ``scene`` with keys of its tables changed, validated exactly as a scene file is
    (the same one-line :class:`~transient.SceneError`, naming the key).

    Each keyword names a table (``scene``, ``mechanism``, ``inertia``, ``load``, …) and gives
    its keys as a TOML file would, unit suffixes included, sub-tables as nested dicts:
    ``scene.replace(inertia={"flywheel": 0.5}, initial={"omega_rpm": 1500})``. A key given with
    another unit replaces the scene's own (``omega_rpm`` replaces ``omega``). A key given as
    None is taken out, in whatever unit the scene has it (TOML has no null): a 4-stroke scene
    made a 2-stroke drops its gas-exchange pressures with ``gas={"p_intake": None,
    "p_exhaust": None}``.

    Examples
    --------
    >>> import transient
    >>> rod = {"model": "two-mass", "mass": 1.752,
    ...        "cg_from_pin_mm": 107.3}
    >>> scene = transient.Scene.from_dict({
    ...     "mechanism": {
    ...         "type": "crank-slider", "crank_radius_mm": 47,
    ...         "rod_length_mm": 148, "bore_mm": 88,
    ...         "piston_mass": 1.52, "crank_mass": 0.912,
    ...         "rod": rod},
    ...     "inertia": {"shaft": 0.02},
    ...     "initial": {"omega_rpm": 1000},
    ...     "run": {"revolutions": 2}})
    >>> heavier = scene.replace(inertia={"flywheel": 0.5})
    >>> heavier.inertia.flywheel, scene.inertia.flywheel
    (0.5, 0.0)
    """
    data = parse_toml(to_toml(scene), "(replace)")
    for table, keys in tables.items():
        if not isinstance(keys, dict):
            raise SceneError(table, f"give the table's keys as a dict, got {type(keys).__name__}")
        _merge(data.setdefault(table, {}), keys)
    return scene_from_dict(data, file="(replace)")


def _merge(base: dict, changes: dict) -> None:
    """``changes`` into the TOML table ``base``, sub-tables merged key by key; a key replaces
    the same quantity written with another unit suffix (or none)."""
    for key, value in changes.items():
        if isinstance(value, dict) and isinstance(base.get(key), dict):
            _merge(base[key], value)
            continue
        stem = _unsuffixed(key)
        for other in [k for k in base if k != key and _unsuffixed(k) == stem]:
            del base[other]
        if value is None:
            base.pop(key, None)
        else:
            base[key] = value


def _unsuffixed(key: str) -> str:
    head, _, suffix = key.rpartition("_")
    return head if head and suffix in ALL_SUFFIXES else key


def scene_from_dict(data: dict, file: str = "", base_dir: Path | None = None) -> Scene:
    """Build and validate a scene from parsed TOML: one dict per table, keys as a scene file
    writes them. Raises :class:`~transient.SceneError`; ``file`` names the scene in its message,
    ``base_dir`` is where the files it names are read from (default the working folder).

    Examples
    --------
    >>> import transient
    >>> rod = {"model": "two-mass", "mass": 1.752,
    ...        "cg_from_pin_mm": 107.3}
    >>> scene = transient.Scene.from_dict({
    ...     "mechanism": {
    ...         "type": "crank-slider", "crank_radius_mm": 47,
    ...         "rod_length_mm": 148, "bore_mm": 88,
    ...         "piston_mass": 1.52, "crank_mass": 0.912,
    ...         "rod": rod},
    ...     "inertia": {"shaft": 0.02},
    ...     "initial": {"omega_rpm": 1000},
    ...     "run": {"revolutions": 2}})
    >>> scene.mechanism.bore  # [m]
    0.088
    """
    base_dir = base_dir or Path.cwd()
    if isinstance(data.get("sweep"), dict) and "mechanism" not in data:
        raise SweepNotScene(file)
    try:
        root = Section(data, "")
        head = root.sub("scene")
        name = _label(head, Named(Path(file).stem if file else "scene", "the file's name"))
        if not name.strip():
            raise SceneError(head.key(head.written.get("name", "name")),
                             "must not be empty; it names the result (leave it out to use the "
                             "file's name)")
        description = head.string("description", "")
        head.finish()
        ms = root.sub("mechanism", required=True)
        kind = ms.string("type", choices=tuple(MECHANISMS))
        mech = MECHANISMS[kind].read(ms)
        ms.finish()
        sections: dict[str, Any] = {}
        si = root.sub("inertia")
        sections["inertia"] = Inertia(si.number("shaft", "inertia", 0.0, ge=0.0),
                                      si.number("flywheel", "inertia", 0.0, ge=0.0),
                                      si.number("load", "inertia", 0.0, ge=0.0))
        si.finish()
        sg = root.sub("gas")
        sections["gas"] = _read_gas(sg, base_dir, mech.strokes,
                                    Named(mech.n_cylinders, mech.cylinder_count))
        sg.finish()
        sl = root.sub("load")
        sections["load"] = _read_load(sl, base_dir, mech.cycle)
        sl.finish()
        ss = root.sub("starter")
        torque = ss.number("torque", "torque", 0.0, ge=0.0)
        noload = ss.number("noload_speed", "speed", 1.0, gt=0.0)
        cutout = ss.number("cutout_speed", "speed", Named(noload, "noload_speed"), gt=0.0,
                           le=Named(noload, "noload_speed"))
        sections["starter"] = Starter(torque, noload, cutout)
        ss.finish()
        sgv = root.sub("governor")
        sections["governor"] = _read_governor(sgv)
        sgv.finish()
        s0 = root.sub("initial")
        sections["initial"] = Initial(s0.number("phi", "angle", 0.0),
                                      s0.number("omega", "speed", 0.0))
        s0.finish()
        sr = root.sub("run", required=True)
        sections["run"] = _read_run(sr)
        sr.finish()
        sv = root.sub("solver")
        sections["solver"] = Solver(
            method=sv.string("method", "dop853", choices=METHODS),
            rtol=sv.number("rtol", "1", 1e-8, gt=0.0, lt=1.0),
            atol=sv.number("atol", "state", 1e-10, gt=0.0),
            switch_speed=sv.number("switch_speed", "speed", math.pi / 3.0, gt=0.0),
            max_step=sv.number("max_step", "angle", math.pi, gt=0.0),
            domain=sv.string("domain", "auto", choices=("auto", "time")),
            fixed_step=sv.number("fixed_step", "angle", 0.0, ge=0.0),
            kinematics=sv.string("kinematics", "exact", choices=("exact", "tabulated")),
            table_tolerance=sv.number("table_tolerance", "1", 0.0, ge=0.0, lt=1.0),
            multirevolution=sv.flag("multirevolution", False),
            envelope_rtol=sv.number("envelope_rtol", "1", ENVELOPE_RTOL, gt=0.0, lt=1.0))
        sv.finish()
        so = root.sub("output")
        # (every sample is written: a run must stay finite)
        sections["output"] = Output(so.integer("samples_per_rev", 72, ge=4,
                                               le=MAX_SAMPLES_PER_REV),
                                    so.number("dt", "time", 0.0, ge=MIN_OUTPUT_DT, or_zero=True))
        so.finish()
        sf = root.sub("friction")
        sections["friction"] = _read_friction(sf, mech, base_dir, sections["gas"].model)
        sf.finish()
        sa = root.sub("analysis")
        sections["analysis"] = _read_analysis(sa)
        sa.finish()
        root.known.append("shaft")
        if root.has("shaft"):  # (absent: the rigid shaft, nothing read or checked)
            sh = root.sub("shaft")
            sections["shaft"] = read_shaft(sh, mech, sections["inertia"])
            sh.finish()
        root.finish()
        scene = Scene(name=name, description=description, mechanism=mech, **sections)
        least_inertia, lever = check_consistency(scene)
        table = check_gas_table(scene, sg)
        try:
            check_magnitudes(scene, least_inertia, lever, table)
        except SceneError as exc:  # (reported under the key as written: omega_rpm, p_z_MPa, …)
            for section in (s0, sg, sl, ss, sr):
                section.rename(exc)
            raise
        check_analysis(scene)
        try:
            check_work(scene)
        except SceneError as exc:  # (reported under the key as written: max_step_deg, …)
            for section in (s0, sr, sv, so, sa):
                section.rename(exc)
            raise
        return scene
    except SceneError as exc:
        exc.file = exc.file or file
        exc.args = (exc.line(),)
        raise


def _label(s: Section, default: Named) -> str:
    """The ``name`` of a table (the scene's, a pair's): it labels terminal lines, figures and
    result files, so a character a terminal would act on (an escape sequence, a newline) is
    refused, not printed."""
    name = s.string("name", default)
    bad = next((c for c in name if not c.isprintable()), None)
    if bad is not None:
        raise SceneError(s.key(s.written.get("name", "name")),
                         f"holds the control character {show_value(bad)} (character "
                         f"{name.index(bad) + 1}); a name labels terminal lines, figures and "
                         f"results: give printable text")
    return name


def _read_gas(s: Section, base_dir: Path, strokes: int, n_cylinders: Named) -> Gas:
    gas = _read_gas_model(s, base_dir, strokes)
    if gas.model == "none":
        if "cylinders" in s.data:
            raise SceneError(s.key("cylinders"), "varies the gas force of cylinders that have "
                                                 "none; give a gas model (gas.model) or leave "
                                                 "[[gas.cylinders]] out")
        return gas
    cylinders = _read_cylinders(s, n_cylinders, burns=gas.model != "compressor")
    if gas.model == "compressor":  # no fuel: nothing to inject
        return replace(gas, cylinders=cylinders)
    cycle = Named(2.0 * math.pi * strokes / 2, "the cycle (mechanism.strokes × 180°)")
    at_once = Named(None, "not set: every cylinder follows the fuel command at once")
    return replace(gas, injection=s.number("injection", "angle", at_once, ge=0.0, lt=cycle),
                   cylinders=cylinders)


def _read_cylinders(s: Section, n_cylinders: Named, burns: bool = True) -> tuple[Cylinder, ...]:
    """The [[gas.cylinders]] entries: per cylinder its fuel and pressure factors, cut-out and
    misfires (:class:`~.records.Cylinder`), sorted by cylinder. A model that ``burns`` no fuel
    (a compressor) takes the pressure factor only."""
    out: list[Cylinder] = []
    seen: dict[int, int] = {}
    top = MAX_CYLINDER_FACTOR
    for i, cs in enumerate(s.tables("cylinders")):
        other = [k for k in cs.data if k not in ("cylinder", "pressure")]
        if not burns and other:
            raise SceneError(cs.key(other[0]), "a compressor burns no fuel: its "
                                               "[[gas.cylinders]] entries take 'cylinder' and "
                                               "'pressure' only")
        k = cs.integer("cylinder", ge=1, le=n_cylinders)
        if k in seen:
            raise SceneError(cs.key("cylinder"), f"cylinder {k} has an entry already "
                                                 f"({s.key('cylinders')}[{seen[k]}]); give each "
                                                 f"cylinder one entry")
        seen[k] = i
        fuel = cs.number("fuel", "1", 1.0, ge=0.0, le=top)
        pressure = cs.number("pressure", "1", 1.0, ge=0.0, le=top)
        cut_out = cs.flag("cut_out", False)
        if cut_out and cs.written.get("fuel"):
            raise SceneError(cs.key("cut_out"), "is given with 'fuel'; a cut-out cylinder gets "
                                                "no fuel (factor 0): give one of them")
        cycles = cs.integers("misfire_cycles", ())
        for c in cycles:
            if c < 1:
                raise SceneError(cs.key("misfire_cycles"), f"must hold cycle numbers ≥ 1, got "
                                                           f"{c}; cycle 1 is the one in "
                                                           f"progress at the start")
        offset = cs.number("combustion_offset", "angle", 0.0, ge=-MAX_COMBUSTION_OFFSET,
                           le=MAX_COMBUSTION_OFFSET)
        entry = Cylinder(cylinder=k, fuel=0.0 if cut_out else fuel, pressure=pressure,
                         cut_out=cut_out, misfire_cycles=tuple(sorted(set(cycles))),
                         misfire_every=cs.integer("misfire_every", 0, ge=0),
                         misfire_rate=cs.number("misfire_rate", "1", 0.0, ge=0.0, le=1.0),
                         misfire_seed=cs.integer("misfire_seed", 0, ge=0,
                                                 le=Named(2 ** 63 - 1, "2⁶³ − 1")),
                         combustion_offset=offset)
        cs.finish()
        out.append(entry)
    return tuple(sorted(out, key=lambda c: c.cylinder))


def _read_gas_model(s: Section, base_dir: Path, strokes: int) -> Gas:
    model = s.string("model", "none",
                     choices=("none", "table", "mixed-cycle", "trapezoid", "wiebe", "compressor"))
    if model == "trapezoid":  # a force per piston [N] (Antonyuk §4): no pressure, no p0
        amplitude = s.number("amplitude", "force", ge=0.0)
        duration = s.number("duration", "angle", math.pi, gt=0.0,
                            lt=Named(math.pi * strokes, "the cycle (mechanism.strokes × 180°)"))
        return Gas(model="trapezoid", p0=0.0, amplitude=amplitude, duration=duration,
                   ramp=s.number("ramp", "angle", gt=0.0, le=Named(duration / 2.0,
                                                                   "duration/2")))
    if model == "table":
        return _read_gas_table(s, base_dir)
    p0 = s.number("p0", "pressure", 1.0e5, ge=0.0)
    if model == "none":
        return Gas(model="none", p0=p0)
    if model == "wiebe":
        return _read_wiebe(s, p0, strokes)
    if model == "compressor":
        return _read_compressor(s, p0)
    p_in, p_ex = _gas_exchange(s, strokes, gt=0.0)
    ratio = s.number("compression_ratio", "1", gt=1.0)
    p_a = s.number("p_a", "pressure", gt=0.0)
    n1 = s.number("n1", "1", gt=1.0)
    try:
        p_c = p_a * ratio ** n1  # (the compression's end, which the combustion starts from)
    except OverflowError:
        p_c = math.inf
    return Gas(
        model="mixed-cycle", p0=p0, compression_ratio=ratio, p_a=p_a, n1=n1,
        p_z=s.number("p_z", "pressure", ge=Named(p_c, "p_a · compression_ratio^n1")),
        rho=s.number("rho", "1", ge=1.0, lt=Named(ratio, "compression_ratio")),
        n2=s.number("n2", "1", gt=1.0), p_intake=p_in, p_exhaust=p_ex)


def _read_compressor(s: Section, p0: float) -> Gas:
    """``model = "compressor"`` (:mod:`transient.forces.compressor`): the clearance gas must
    re-expand to p_s before the bottom dead centre and the compression reach p_d before the top
    one, c·((p_d/p_s)^(1/n) − 1) < 1 for the smaller exponent."""
    n = s.number("n", "1", gt=1.0)
    p_s = s.number("p_suction", "pressure", gt=0.0)
    p_d = s.number("p_discharge", "pressure", gt=Named(p_s, "p_suction"))
    n_e = s.number("n_reexpansion", "1", Named(n, "n"), gt=1.0)
    top = 1.0 / ((p_d / p_s) ** (1.0 / min(n, n_e)) - 1.0)
    clearance = s.number("clearance_ratio", "1", gt=0.0, lt=Named(
        top, "1/((p_discharge/p_suction)^(1/min(n, n_reexpansion)) − 1)"))
    return Gas(model="compressor", p0=p0, p_suction=p_s, p_discharge=p_d, n=n,
               n_reexpansion=n_e, clearance_ratio=clearance)


def _gas_exchange(s: Section, strokes: int, **bounds: Any) -> tuple[float, float]:
    """``p_intake`` and ``p_exhaust`` [Pa], the constant pressures of a 4-stroke's intake and
    exhaust strokes (required, within ``bounds``, :meth:`Section.number`'s). A 2-stroke has no
    such strokes: the cycle models scavenge it to p_a at bottom dead centre, so the keys would
    mean nothing and are refused (0 in the record)."""
    if strokes == 4:
        return (s.number("p_intake", "pressure", **bounds),
                s.number("p_exhaust", "pressure", **bounds))
    for name in ("p_intake", "p_exhaust"):
        written = next((k for k in s.data if _unsuffixed(k) == name), None)
        if written is not None:
            raise SceneError(s.key(written), "a two-stroke cycle (mechanism.strokes = 2) has "
                                             "no intake or exhaust stroke: it is scavenged to "
                                             "p_a at bottom dead centre; leave p_intake and "
                                             "p_exhaust out (they are for strokes = 4)")
    return 0.0, 0.0


#: The default of a pressure table's ``p`` and ``force``: one of them is required.
P_OR_FORCE = Named((), "none: give p or force")


def _read_gas_table(s: Section, base_dir: Path) -> Gas:
    """``model = "table"``: absolute pressures ``p`` (with the crankcase's ``p0`` and optionally
    the motored ``motored_p``) or forces on each piston ``force`` (applied as they are: no
    ``p0``) at the local angles ``phi``, inline or from a CSV ``file``."""
    if s.has("file"):
        phi, column, values, motored = _read_diagram_csv(s, base_dir)
        force = column in FORCE_COLUMNS
    else:
        phi = s.numbers("phi", "angle")
        values = s.numbers("force", "force", P_OR_FORCE)
        force = bool(values)
        if force and s.has("p", "pressure"):
            raise SceneError(s.key("force"), "is given with 'p'; a table holds the pressure in "
                                             "the cylinder or the force on its piston: give one "
                                             "of them")
        if not force and not s.has("p", "pressure"):
            s.numbers("p", "pressure", P_OR_FORCE)  # (a 'p' with a wrong suffix is named first)
            raise SceneError(s.key("p"), "is missing; give the pressures 'p' (or 'p_bar', "
                                         "'p_MPa') or the forces on the piston 'force' (or "
                                         "'force_kN'), one per angle")
        values = values or s.numbers("p", "pressure", P_OR_FORCE)
        motored = s.numbers("motored_p", "pressure", ())
    if force and motored:
        key = "file" if "file" in s.written else s.written.get("motored_p", "motored_p")
        raise SceneError(s.key(key), "gives motored pressures with forces on the piston; the "
                                     "motored curve goes with the pressures 'p' it lies under")
    p0 = 0.0 if force else s.number("p0", "pressure", 1.0e5, ge=0.0)
    corners = s.numbers("corners", "angle", ())
    interp = s.string("interpolation", "pchip", choices=("pchip", "spline", "linear"))
    return Gas(model="table", p0=p0, phi=phi, p=() if force else values,
               force=values if force else (), motored_p=motored, corners=corners,
               interpolation=interp)


def _read_wiebe(s: Section, p0: float, strokes: int) -> Gas:
    """``model = "wiebe"``: the cycle's pressures in [gas], the combustion in [gas.wiebe].

    Ranges of single keys are checked here; what needs several of them (the combustion inside
    the closed part, γ(T) > 1 at intake closing) by :mod:`transient.forces.wiebe` when the table
    is built, still inside :func:`~transient.load_scene` (:func:`~.checks.check_gas_table`).
    """
    d = Wiebe()
    ratio = s.number("compression_ratio", "1", gt=1.0)
    p_a = s.number("p_a", "pressure", gt=0.0)
    p_in, p_ex = _gas_exchange(s, strokes, ge=0.0)
    w = s.sub("wiebe", required=True)
    wiebe = Wiebe(
        start=w.number("start", "angle"), duration=w.number("duration", "angle", gt=0.0),
        fuel_mass=w.number("fuel_mass", "mass", ge=0.0), a=w.number("a", "1", d.a, gt=0.0),
        m=w.number("m", "1", d.m, gt=-1.0),
        lhv=w.number("lhv", "specific energy", d.lhv, gt=0.0),
        efficiency=w.number("efficiency", "1", d.efficiency, gt=0.0, le=1.0),
        gamma=w.number("gamma", "1", d.gamma, gt=1.0, le=Named(MAX_GAMMA, "5/3")),
        gamma_slope=w.number("gamma_slope", "per kelvin", d.gamma_slope),
        gamma_t_ref=w.number("gamma_t_ref", "temperature", d.gamma_t_ref, gt=0.0),
        t_a=w.number("t_a", "temperature", d.t_a, gt=0.0),
        intake_closing=w.number("intake_closing", "angle",
                                Named(None, "the BDC before the firing TDC")),
        exhaust_opening=w.number("exhaust_opening", "angle",
                                 Named(None, "the BDC after the firing TDC")),
        step=w.number("step", "angle", d.step, ge=MIN_WIEBE_STEP),
        tolerance=w.number("tolerance", "1", d.tolerance, ge=1e-13, le=1e-3))
    w.finish()
    woschni = None
    if s.has("woschni"):
        h, dh = s.sub("woschni"), Woschni()
        woschni = Woschni(c1=h.number("c1", "1", dh.c1, ge=0.0),
                          c2=h.number("c2", "woschni c2", dh.c2, ge=0.0),
                          wall_temperature=h.number("wall_temperature", "temperature",
                                                    dh.wall_temperature, gt=0.0))
        h.finish()
    return Gas(model="wiebe", p0=p0, compression_ratio=ratio, p_a=p_a, p_intake=p_in,
               p_exhaust=p_ex, wiebe=wiebe, woschni=woschni)


#: Column names of a pressure or force table (CSV) and their factors to SI.
ANGLE_COLUMNS = {"phi_deg": math.pi / 180.0, "phi": 1.0}
PRESSURE_COLUMNS = {"p": 1.0, "p_bar": 1e5, "p_MPa": 1e6, "p_Pa": 1.0}
FORCE_COLUMNS = {"force": 1.0, "force_N": 1.0, "force_kN": 1e3}


def _read_diagram_csv(s: Section, base_dir: Path):
    """Indicator diagram (or force diagram) from a CSV with an angle column and a pressure or a
    force column (units in names): the angles, the name of that column and its values, and the
    values of a motored pressure column (``motored_p_bar`` …) if it has one, else ()."""
    motored_columns = {f"motored_{c}": f for c, f in PRESSURE_COLUMNS.items()}
    (_, phi), (column, values), (_, motored) = _read_csv(s, base_dir, {
        "angle": ANGLE_COLUMNS, "pressure or force": {**PRESSURE_COLUMNS, **FORCE_COLUMNS},
        "motored pressure": motored_columns}, optional=("motored pressure",))
    return phi, column, values, motored


def _read_csv(s: Section, base_dir: Path, groups: dict[str, dict[str, float]],
              optional: tuple[str, ...] = ()):
    """The CSV file named by the key ``file`` of ``s`` (relative to the scene): for each group
    of column names (what it is → {column name: factor to SI}) the first column of the header
    in it, as ``(name, values in SI)``; a group in ``optional`` that the header lacks gives
    ``(None, ())``. Every error names the file under the key ``file``."""
    name = s.string("file")
    try:
        path = (base_dir / name).resolve()
        there = path.exists()
    except (OSError, ValueError):  # a name too long for the system, or holding a NUL
        there = False
    if not there:
        raise SceneError(s.key("file"), f"no such file {show_value(name)}; give a CSV path "
                                        f"relative to the scene")
    try:
        rows = table_rows(read_text(path, "table"))
        header = [h.strip() for h in rows[0][1]] if rows else []
        found = {what: next((c for c in header if c in columns), None)
                 for what, columns in groups.items()}
        if any(c is None and what not in optional for what, c in found.items()):
            needs = " and ".join(f"{'an' if what[0] in 'aeiou' else 'a'} {what} column "
                                 f"({', '.join(columns)})" for what, columns in groups.items()
                                 if what not in optional)
            raise SceneError("(line)", f"needs {needs}; header is {show_value(header)}")
        out = [(c, _table_column(rows[1:], header.index(c), c, groups[what][c]))
               if c is not None else (None, ()) for what, c in found.items()]
    except SceneError as exc:  # (placed here: the message names the table, the key the scene's)
        raise SceneError(s.key("file"), f"{path.name}: {exc.message}") from None
    return out


def _table_column(rows, index: int, column: str, factor: float) -> tuple[float, ...]:
    """Column ``index`` of a table's data rows in SI; a short row or a field that is no finite
    number is an error naming its line."""
    out = []
    for number, fields in rows:
        if index >= len(fields):
            raise SceneError("(line)", f"line {number} has {len(fields)} field(s); column "
                                       f"{column} is field {index + 1}")
        out.append(table_number(fields[index], number, column) * factor)
    return tuple(out)


def _read_friction(s: Section, mech, base_dir: Path, gas_model: str) -> Friction:
    """The [friction] table: a policy and an array of [[friction.pairs]] between neighbouring
    links of the mechanism (shaft side first), each with its friction model; a constant-η or
    mapped pair into the cylinders (the last link, ``gas_model`` its gas) needs gas forces to
    pass on."""
    policy = s.string("policy", "power-flow", choices=POLICIES)
    sections = s.tables("pairs")
    raw = [dict(ps.data) for ps in sections]  # (as written, for the wedging checks' messages)
    pairs: list[Pair] = []
    seen: dict[tuple[str, ...], int] = {}
    for i, ps in enumerate(sections):
        model = ps.string("model", "constant-eta", choices=PAIR_MODELS)
        links = mech.links
        reacting = provides(mech, "reaction-friction")
        if model == "reaction":
            if not reacting:
                raise SceneError(ps.key("model"), f"friction on the reactions is not implemented "
                                                  f"for {mech.name!r}; use model = "
                                                  f"\"constant-eta\" here")
            links = mech.reaction_links
        hint = ""
        if model != "reaction" and reacting and mech.reaction_links != links:
            hint = (f" (pairs with model = \"reaction\" join "
                    f"{' – '.join(mech.reaction_links)})")
        if model == "reaction" and mech.reaction_joints != tuple(zip(links, links[1:])):
            between = _joint(ps, mech)
        else:
            between = _between(ps, links, hint)
        if model != "reaction" and between[1] == links[-1] and gas_model == "none":
            raise SceneError(ps.key("between"), f"{list(between)} passes on the gas forces' "
                                                f"work, and this scene has none (gas.model = "
                                                f"\"none\"); give a gas model, or join other "
                                                f"links of {' – '.join(links)}")
        ideal = mech.ideal_reaction_joints if model == "reaction" else {}
        if between[0] in ideal:
            allowed = ", ".join(f"[{a!r}, {b!r}]" for a, b in zip(links, links[1:])
                                if a not in ideal)
            raise SceneError(ps.key("between"),
                             f"{list(between)} ({ideal[between[0]]}) cannot have friction on "
                             f"its reactions: the {mech.name} keeps them ideal; reaction pairs "
                             f"join {allowed}")
        if tuple(between) in seen:
            raise SceneError(ps.key("between"), f"the same pair as "
                                                f"{s.key('pairs')}[{seen[tuple(between)]}]")
        seen[tuple(between)] = i
        name = _label(ps, Named(f"{between[0]}-{between[1]}", "its two links, as “crank-rod”"))
        if model == "reaction":
            pair = _reaction_pair(ps, between, name, slider=between[1] == links[-1])
        elif model == "table":
            pair = _table_pair(ps, between, name, base_dir)
        else:
            pair = Pair(between=between, eta_forward=_efficiency(ps, "eta_forward"),
                        eta_backward=_efficiency(ps, "eta_backward"), name=name)
        ps.finish()
        twin = next((j for j, q in enumerate(pairs) if q.name == pair.name), None)
        if twin is not None:
            raise SceneError(ps.key("name"), f"{show_value(pair.name)} names "
                                             f"{s.key('pairs')}[{twin}] "
                                             f"too; give each pair its own name (it labels the "
                                             f"pair's result columns and reports)")
        pairs.append(pair)
    if any(p.model == "reaction" for p in pairs):
        _check_mixed(s, mech, policy, pairs)
        joints = reaction_joints(mech)
        pairs.sort(key=lambda p: joints.index(p.between))
        mech.check_wedging(s, pairs, raw)
    else:
        pairs.sort(key=lambda p: mech.links.index(p.between[0]))
    return Friction(policy, tuple(pairs))


def _check_mixed(s: Section, mech, policy: str, pairs) -> None:
    """Among reaction pairs, a pair of another model only where the mechanism's solver takes it
    (``transient.core.model.reactions``, *A constant-η or mapped pair at the main bearings*): at the
    joint that couples the shaft to the mechanism, under the power-flow policy."""
    coupling = mech.shaft_coupling
    for i, p in enumerate(pairs):
        if p.model == "reaction":
            continue
        key = f"{s.key('pairs')}[{i}]"
        if coupling is None:
            raise SceneError(f"{key}.model", f"{p.model!r} among reaction pairs: the "
                                             f"{mech.name}'s reaction pairs do not mix with "
                                             f"others; give every pair model = \"reaction\", or "
                                             f"none")
        where = f"[{coupling[0]!r}, {coupling[1]!r}]"
        if tuple(p.between) != coupling:
            raise SceneError(f"{key}.between", f"a {p.model} pair among reaction pairs joins "
                                               f"{where} (the main bearings), not "
                                               f"{list(p.between)}")
        if policy != "power-flow":
            raise SceneError(s.key("policy"), f"{policy!r} with a {p.model} pair among "
                                              f"reaction pairs; their mix follows the "
                                              f"\"power-flow\" policy")


def _link_names(ps: Section, links, allowed: str, known: str) -> tuple[str, str]:
    """The key ``between``: two names of ``links``; ``allowed`` ends the message of a malformed
    value, ``known`` that of an unknown link."""
    between = ps.raw("between", "two link names", required=True)
    between = None if between is MISSING else between
    if (not isinstance(between, list) or len(between) != 2
            or not all(isinstance(b, str) for b in between)):
        raise SceneError(ps.key("between"), f"must be two link names, got {show_value(between)}; "
                                            f"{allowed}")
    for b in between:
        if b not in links:
            raise SceneError(ps.key("between"), f"unknown link {show_value(b)}; {known}")
    return between[0], between[1]


def _joint(ps: Section, mech) -> tuple[str, str]:
    """The two links of a reaction pair of a mechanism whose joints do not form a chain (its
    ``reaction_joints``), shaft side first."""
    links, joints = mech.reaction_links, mech.reaction_joints
    allowed = ", ".join(f"[{a!r}, {b!r}]" for a, b in joints)
    pair = _link_names(ps, links, f"the joints are {allowed}",
                       f"the links of {mech.name!r} are {', '.join(links)}, joined as {allowed}")
    if pair[::-1] in joints:
        raise SceneError(ps.key("between"), f"give the shaft-side link first: "
                                            f"[{pair[1]!r}, {pair[0]!r}]")
    if pair not in joints:
        raise SceneError(ps.key("between"), f"{pair[0]!r} and {pair[1]!r} are not joined in "
                                            f"{mech.name!r}; the joints are {allowed}")
    return pair


def _between(ps: Section, links: tuple[str, ...], hint: str) -> tuple[str, str]:
    """The pair's two links, neighbours in ``links``, shaft side first (``hint`` ends the message
    of an unknown link)."""
    chain = " – ".join(links)
    between = _link_names(ps, links, f"the links are {chain}", f"the links are {chain}{hint}")
    ia, ib = links.index(between[0]), links.index(between[1])
    if abs(ia - ib) != 1:
        raise SceneError(ps.key("between"),
                         f"{between[0]!r} and {between[1]!r} are not neighbours; a pair joins "
                         f"two adjacent links of the chain {chain}")
    if ib < ia:
        raise SceneError(ps.key("between"), f"give the shaft-side link first: "
                                            f"[{between[1]!r}, {between[0]!r}]")
    return between[0], between[1]


def _reaction_pair(ps: Section, between: tuple[str, str], name: str, slider: bool) -> Pair:
    """A pair with friction on its reaction: a journal or pin (μ, radius, viscous) or the piston
    in its cylinder (μ, ring force, ring pressure share, viscous)."""
    mu = ps.number("mu", "1", ge=0.0, le=1.0)
    if slider:
        return Pair(between=between, eta_forward=1.0, eta_backward=1.0, name=name,
                    model="reaction", mu=mu,
                    viscous=ps.number("viscous", "linear damping", 0.0, ge=0.0),
                    ring_force=ps.number("ring_force", "force", 0.0, ge=0.0),
                    ring_pressure=ps.number("ring_pressure", "1", 0.0, ge=0.0, le=1.0))
    return Pair(between=between, eta_forward=1.0, eta_backward=1.0, name=name, model="reaction",
                mu=mu, radius=ps.number("radius", "length", gt=0.0),
                viscous=ps.number("viscous", "rotary damping", 0.0, ge=0.0))


#: Column names of an efficiency map (CSV) and their factors to SI.
MAP_COLUMNS = {"speed": {"speed_rpm": math.pi / 30.0, "speed": 1.0}, "torque": {"torque": 1.0},
               "forward efficiency": {"eta_forward": 1.0},
               "backward efficiency": {"eta_backward": 1.0}}


def _table_pair(ps: Section, between: tuple[str, str], name: str, base_dir: Path) -> Pair:
    """A pair whose efficiencies are maps over |ω| and |S| (:mod:`.eta_map`): from a CSV file
    (``file``: one row per grid point, columns speed_rpm or speed, torque, eta_forward,
    eta_backward) or inline (``speed``, ``torque``, and ``eta_forward``, ``eta_backward`` as one
    row per speed)."""
    if ps.has("file"):
        inline = ("speed", "speed_rpm", "torque", "eta_forward", "eta_backward")
        for k in (k for k in inline if k in ps.data):
            raise SceneError(ps.key(k), "is given with 'file'; give the map in the file or "
                                        "inline, not both")
        ps_file = str(ps.data["file"])
        cols = [c for _, c in _read_csv(ps, base_dir, MAP_COLUMNS)]
        points = [(i + 1, *vals) for i, vals in enumerate(zip(*cols))]
        try:  # (placed as _read_csv places its errors: the key the scene's, the file named)
            speed, torque, fwd, bwd = grid_from_points("(grid)", points)
            check_map(lambda k: f"column {k}", speed, torque, fwd, bwd)
        except SceneError as exc:
            raise SceneError(ps.key("file"), f"{Path(ps_file).name}: {exc.key}: "
                                             f"{exc.message}") from None
    else:
        speed = ps.numbers("speed", "speed")
        torque = ps.numbers("torque", "torque")
        fwd = _rows(ps, "eta_forward")
        bwd = _rows(ps, "eta_backward")
        check_map(lambda k: ps.key(ps.written.get(str(k), str(k))), speed, torque, fwd, bwd)
    return Pair(between=between, eta_forward=1.0, eta_backward=1.0, name=name, model="table",
                speed=speed, torque=torque, eta_forward_map=fwd, eta_backward_map=bwd)


def _rows(ps: Section, name: str) -> tuple[tuple[float, ...], ...]:
    """A map's values inline: a list of rows (one per speed) of finite numbers."""
    value = ps.raw(name, "rows of numbers", required=True)
    if value is MISSING:
        raise SceneError(ps.key(name), "is missing; give one row per speed of one value per "
                                       "torque, e.g. [[0.97, 0.98], [0.96, 0.975]]")
    if (not isinstance(value, list) or not value
            or not all(isinstance(r, list) and all(finite_number(v) for v in r) for r in value)):
        raise SceneError(ps.key(name), f"must be a list of rows of finite numbers (one row per "
                                       f"speed), got {show_value(value)}")
    return tuple(tuple(float(v) for v in r) for r in value)


def _efficiency(s: Section, name: str) -> float:
    """An efficiency in (0, 1]; η ≤ 0 would be a self-locking pair (the paper's ξ regime),
    which the model excludes."""
    return s.number(name, "1", gt=0.0, le=1.0)


def _read_load(s: Section, base_dir: Path, cycle: float) -> Load:
    """The [load] table: resisting torques (``torque`` of either sign), a generator, a load from
    data ([load.table]) and the schedule of their scale."""
    torque = s.number("torque", "torque", 0.0)
    linear = s.number("linear", "rotary damping", 0.0, ge=0.0)
    fan = s.number("fan", "quadratic rotary damping", 0.0, ge=0.0)
    power = s.number("generator_power", "power", 0.0, ge=0.0)
    # (below it the torque −P/ω is held at −P/ω_min, finite at rest)
    w_min = s.number("generator_min_speed", "speed",
                     Named(MISSING if power > 0.0 else 0.0,
                           "required with a generator_power, else 0"),
                     ge=0.0, gt=Named(0.0 if power > 0.0 else -math.inf,
                                      "0 with a generator_power"))
    times = s.numbers("schedule_time", "time", ())
    revs = s.numbers("schedule_revolutions", "revolutions", ())
    scale = s.numbers("schedule_scale", "1", (), ge=0.0)  # (it multiplies a resisting load)
    if times and revs:
        raise SceneError(s.key("schedule_revolutions"),
                         "given together with 'schedule_time'; a schedule runs against time or "
                         "against revolutions: give one of them")
    name, x = ("schedule_time", times) if times else ("schedule_revolutions", revs)
    if scale and not x:
        raise SceneError(s.key("schedule_scale"), "has no abscissae; give 'schedule_time' [s] or "
                                                  "'schedule_revolutions' with one entry per "
                                                  "value")
    if x and not scale:
        raise SceneError(s.key(name), "has no values; give 'schedule_scale', the load's scale "
                                      "at each entry")
    if len(x) != len(scale):
        raise SceneError(s.key("schedule_scale"), f"needs as many entries as {name!r}; got "
                                                  f"{len(scale)} and {len(x)}")
    for i in range(1, len(x)):
        a, b = x[i - 1], x[i]
        if b < a:
            raise SceneError(s.key(name), f"must not decrease, but {b:g} follows {a:g} (entry "
                                          f"{i + 1}); a step is two equal entries, a ramp two "
                                          f"increasing ones")
        if i >= 2 and x[i - 2] == a == b:
            raise SceneError(s.key(name), f"{b:g} appears three times in a row (entries {i - 1} "
                                          f"to {i + 1}); a step is two equal entries: the value "
                                          f"before and the value after")
        if 0.0 < b - a < SCHEDULE_MIN_GAP * max(1.0, abs(a), abs(b)):
            raise SceneError(s.key(name), f"{a!r} and {b!r} (entries {i} and {i + 1}) are closer "
                                          f"than {SCHEDULE_MIN_GAP:g} (relative); give equal "
                                          f"entries for a step, or a longer ramp")
    extra = s.number("inertia", "inertia", 0.0, ge=0.0)
    at = s.number("inertia_time", "time", Named(MISSING if extra > 0.0 else 0.0,
                                                "required with an inertia > 0"), gt=0.0)
    table = None
    s.known.append("table")
    if s.has("table"):
        st = s.sub("table")
        table = _read_load_table(st, base_dir, cycle)
        st.finish()
        if table.abscissa == "time" and revs:
            raise SceneError(st.key("time"), "a load in time with a schedule in revolutions: the "
                                             "load's corners are all in time or all in "
                                             "revolutions; give the schedule in 'schedule_time'")
    return Load(torque, linear, fan, power, w_min, times, revs, scale, extra, at, table)


#: The abscissae of [load.table]: key (its CSV column names, with their factors to SI), the
#: quantity kind of its unit suffixes, and what it is
#: (:data:`transient.forces.load_table.ABSCISSAE`).
LOAD_TABLE_ABSCISSAE = {
    "speed": ("speed", {"speed": 1.0, "speed_rpm": math.pi / 30.0}),
    "phi": ("angle", {"phi": 1.0, "phi_deg": math.pi / 180.0}),
    "time": ("time", {"time": 1.0}),
}


#: The default of each abscissa of [load.table]: exactly one of them is required, or a file.
ONE_ABSCISSA = Named((), "none: give one of speed, phi, time (or a file)")


def _read_load_table(s: Section, base_dir: Path, cycle: float) -> LoadTable:
    """``[load.table]``: one abscissa (``speed``, ``phi`` or ``time``, with unit suffixes) and
    ``torque`` inline, or a CSV ``file`` with such columns; the abscissae strictly increasing,
    angles within one cycle (a point at the cycle's end only as the repeat of the one at 0)."""
    interpolation = s.string("interpolation", "linear", choices=INTERPOLATIONS)
    if s.has("file"):
        columns = {n: c for _, (_, cols) in LOAD_TABLE_ABSCISSAE.items() for n, c in cols.items()}
        file = Path(str(s.data["file"])).name
        (column, x), (_, torque) = _read_csv(s, base_dir, {"abscissa": columns,
                                                           "torque": {"torque": 1.0}})
        key = s.key("file")
        name = next(n for n, (_, cols) in LOAD_TABLE_ABSCISSAE.items() if column in cols)
        where = f"{file}, column {column}: "
    else:
        given = [n for n, (kind, _) in LOAD_TABLE_ABSCISSAE.items() if s.has(n, kind)]
        if not given:  # (a key with a unit suffix its quantity does not take is named first)
            for n, (kind, _) in LOAD_TABLE_ABSCISSAE.items():
                s.numbers(n, kind, ONE_ABSCISSA)
        if len(given) != 1:
            names = ", ".join(repr(n) for n in LOAD_TABLE_ABSCISSAE)
            what = "none" if not given else " and ".join(repr(n) for n in given)
            raise SceneError(s.key(given[1] if len(given) > 1 else "torque"),
                             f"needs exactly one abscissa of {names} (or a CSV 'file'), got "
                             f"{what}")
        name = given[0]  # (read as optional: any one of them is, none alone is required)
        x = s.numbers(name, LOAD_TABLE_ABSCISSAE[name][0], ONE_ABSCISSA)
        torque = s.numbers("torque", "torque")
        key = s.key(s.written.get(name, name))
        where = ""
        if len(torque) != len(x):
            raise SceneError(s.key("torque"), f"needs one value per entry of {key}; got "
                                              f"{len(torque)} and {len(x)}")
    if len(x) < 2:
        raise SceneError(key, f"{where}needs at least 2 points, got {len(x)}")
    for i in range(1, len(x)):
        if x[i] <= x[i - 1]:
            raise SceneError(key, f"{where}must increase strictly, but entry {i + 1} "
                                  f"({x[i]:g} in SI) follows {x[i - 1]:g}; give each abscissa "
                                  f"once, in increasing order")
    if name == "phi":
        x, torque = _one_cycle(key, where, x, torque, cycle)
    if name == "time" and min(b - a for a, b in zip(x, x[1:])) < SCHEDULE_MIN_GAP * max(
            1.0, *map(abs, x)):
        raise SceneError(key, f"{where}two times closer than {SCHEDULE_MIN_GAP:g} (relative); "
                              f"each is a corner the stepper stops on, give them further apart")
    return LoadTable(tuple(torque), interpolation=interpolation, **{name: tuple(x)})


def _one_cycle(key: str, where: str, x, torque, cycle: float):
    """The points of a load over the cycle in [0, cycle): one at the cycle's end is dropped when
    it repeats the value at 0 (the curve is periodic), else refused."""
    if x[0] < 0.0 or x[-1] > cycle * (1.0 + 1e-12):
        raise SceneError(key, f"{where}angles must lie within one cycle, 0 to "
                              f"{math.degrees(cycle):g}°; got {math.degrees(x[0]):g}° to "
                              f"{math.degrees(x[-1]):g}°")
    if x[-1] >= cycle * (1.0 - 1e-12):
        if x[0] != 0.0 or torque[-1] != torque[0]:
            raise SceneError(key, f"{where}a point at the cycle's end "
                                  f"({math.degrees(cycle):g}°) is the point at 0° again; give it "
                                  f"with the same torque as at 0°, or leave it out")
        x, torque = x[:-1], torque[:-1]
    if len(x) < 2:
        raise SceneError(key, f"{where}needs at least 2 points in the cycle")
    return x, torque


def _read_governor(s: Section) -> Governor:
    model = s.string("model", "none", choices=tuple(GOVERNOR_KEYS))
    if model == "none":
        return Governor()
    if model == "droop":
        full = s.number("speed_full", "speed", gt=0.0)
        zero = s.number("speed_zero", "speed", gt=Named(full, "speed_full"))
        return Governor(model, full, zero)
    d = Governor()
    f_min = Named(s.number("fuel_min", "1", d.fuel_min, ge=0.0), "fuel_min")
    f_max = Named(s.number("fuel_max", "1", d.fuel_max, gt=f_min), "fuel_max")
    if model == "flyweight":
        return Governor(
            model, fuel_min=f_min.value, fuel_max=f_max.value,
            weights=s.integer("weights", d.weights, ge=1),
            weight_mass=s.number("weight_mass", "mass", gt=0.0),
            radius=s.number("radius", "length", gt=0.0),
            arm_ratio=s.number("arm_ratio", "1", d.arm_ratio, gt=0.0),
            gear_ratio=s.number("gear_ratio", "1", d.gear_ratio, gt=0.0),
            sleeve_mass=s.number("sleeve_mass", "mass", 0.0, ge=0.0),
            spring_rate=s.number("spring_rate", "stiffness", ge=0.0),
            spring_preload=s.number("spring_preload", "force", gt=0.0),
            damping=s.number("damping", "linear damping", ge=0.0),
            travel=s.number("travel", "length", gt=0.0))
    gain_p = s.number("gain_p", "1", ge=0.0)
    gain_i = s.number("gain_i", "rate", ge=0.0)
    if gain_p == 0.0 and gain_i == 0.0:
        raise SceneError(s.key("gain_i"), "gain_p and gain_i are both 0: the governor would never "
                                          "move the rack; give gain_i > 0 (isochronous)")
    return Governor(
        model, speed=s.number("speed", "speed", gt=0.0), gain_p=gain_p, gain_i=gain_i,
        gain_d=s.number("gain_d", "time", 0.0, ge=0.0),
        derivative_time=s.number("derivative_time", "time", d.derivative_time, gt=0.0),
        actuator_time=s.number("actuator_time", "time", d.actuator_time, gt=0.0),
        rate_limit=s.number("rate_limit", "rate", 0.0, ge=0.0),
        fuel_min=f_min.value, fuel_max=f_max.value, anti_windup=s.flag("anti_windup", True),
        tracking_time=s.number("tracking_time", "time", 0.0, ge=0.0),
        fuel_initial=s.number("fuel_initial", "1", f_max, ge=f_min, le=f_max))


#: A prescribed speed is constant (``speed``) or a table (``time`` with ``speed_table``).
SPEED_OR_TABLE = Named(MISSING, "required: speed, or time with speed_table")


def _read_run(s: Section) -> Run:
    mode = s.string("mode", "dynamic", choices=("dynamic", "prescribed-speed"))
    t_end = s.number("t_end", "time", math.inf, gt=0.0)
    revs = s.number("revolutions", "revolutions", math.inf, gt=0.0)
    if math.isinf(t_end) and math.isinf(revs):
        raise SceneError(s.key("t_end"), "the run needs an end: give t_end [s] and/or revolutions")
    budgets: dict[str, Any] = {"max_output_bytes": s.number("max_output_bytes", "bytes",
                                            DEFAULT_MAX_OUTPUT_BYTES, gt=0.0),
               "max_steps": s.number("max_steps", "1", DEFAULT_MAX_STEPS, ge=1.0)}
    if mode == "dynamic":
        return Run(mode=mode, t_end=t_end, revolutions=revs, **budgets)
    if s.has("speed", "speed"):
        speed = s.number("speed", "speed", SPEED_OR_TABLE, gt=0.0)
        return Run(mode=mode, t_end=t_end, revolutions=revs, speed=speed, **budgets)
    if not s.has("time") and not s.has("speed_table", "speed"):
        raise SceneError(s.key("speed"), "is missing; a prescribed-speed run needs 'speed' (or "
                                         "'speed_rpm'), or a table 'time' [s] with 'speed_table'")
    time = s.numbers("time", "time", SPEED_OR_TABLE)
    table = s.numbers("speed_table", "speed", SPEED_OR_TABLE, gt=0.0)
    if len(time) != len(table) or len(time) < 2:
        raise SceneError(s.key("speed_table"), f"needs as many entries as 'time' (≥ 2); got "
                                               f"{len(table)} and {len(time)}")
    if any(b <= a for a, b in zip(time, time[1:])):
        raise SceneError(s.key("time"), "must increase strictly")
    interpolation = s.string("interpolation", "linear", choices=INTERPOLATIONS)
    return Run(mode=mode, t_end=min(t_end, time[-1]), revolutions=revs, time=time,
               speed_table=table, interpolation=interpolation, **budgets)


def _read_analysis(s: Section) -> Analysis:
    return Analysis(loads=s.flag("loads", False), orders=s.strings("orders", ()),
                    irregularity=s.flag("irregularity", False),
                    thermodynamics=s.flag("thermodynamics", False),
                    max_order=s.number("max_order", "order", 12.0, gt=0.0),
                    samples_per_cycle=s.integer("samples_per_cycle", 720, ge=16),
                    detrend=s.string("detrend", "auto", choices=DETREND))

