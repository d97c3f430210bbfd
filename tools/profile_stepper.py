"""Where a run's time goes inside the compiled stepper: ``perf`` samples attributed to numba's
functions, and the share of each function's samples spent in copying call arguments on the stack.

numba's machine code has no symbols that ``perf`` can see. This script keeps the object code of
every function numba loads from its cache, finds where each was placed in memory (the address of
one global symbol, the rest at their offsets in the same section) and bins the sample addresses by
function. For each function it also counts the samples on stack moves (``mov`` between a register
and ``(%rsp)``, ``push``): passing the Model tuple to a function that is not inlined copies its
~150 flattened words, and those moves are that copy (register spills count too, so the share is
an upper bound). ``--calls NAME`` attributes a function's stack moves to the call that follows
them (approximately: the moves since the previous call).

Needs ``perf`` and binutils (``nm``, ``objdump``). Run (warm cache)::

    perf record -o /tmp/perf.data .venv/bin/python tools/profile_stepper.py run \
        gots_diesel_governed [REPEATS [SAMPLES_PER_TURN]]
    .venv/bin/python tools/profile_stepper.py report [--calls advance]
"""
from __future__ import annotations

import bisect
import collections
import dataclasses as dc
import re
import subprocess
import sys
from pathlib import Path

CASES = Path(__file__).resolve().parents[1] / "cases"
SYMBOLS = Path("/tmp/transient_jit_symbols.txt")  # address size name object-file
OBJECTS = Path("/tmp/transient_jit_objects")
PERF_DATA = "/tmp/perf.data"
STACK_MOVE = re.compile(r"(mov\s+(%r\w+,0x[0-9a-f]+\(%rsp\)|0x[0-9a-f]+\(%rsp\),%r\w+)|push\s)")


def _text_symbols(obj: Path) -> list[list[str]]:
    out = subprocess.run(["nm", "-S", str(obj)], capture_output=True, text=True).stdout
    return [p for p in (line.split() for line in out.splitlines())
            if len(p) == 4 and p[2] in "TtWw"]


def run(name: str, repeats: int = 20, samples_per_rev: int = 1) -> None:
    """Integrate the scene ``repeats`` times (1000 revolutions, rtol 1e-8, one sample per turn
    unless ``samples_per_rev`` says otherwise, as ``stepper_overhead.py``), after writing the
    address of every loaded numba function."""
    from numba.core import codegen

    loaded = []
    original = codegen.CPUCodeLibrary._set_compiled_object

    def keep(self, value):
        loaded.append((self, value))
        return original(self, value)

    codegen.CPUCodeLibrary._set_compiled_object = keep
    from transient.run import integrate
    from transient.scene import load_scene

    scene = load_scene(CASES / f"{name}.toml")
    scene = dc.replace(scene, output=dc.replace(scene.output, samples_per_rev=samples_per_rev),
                       solver=dc.replace(scene.solver, rtol=1e-8, atol=1e-11))
    integrate(scene, keep=False)  # loads (or compiles) everything
    OBJECTS.mkdir(exist_ok=True)
    rows = []
    for i, (lib, obj_code) in enumerate(loaded):
        obj = OBJECTS / f"{i}.o"
        obj.write_bytes(obj_code)
        syms = _text_symbols(obj)
        # one global symbol's address places the whole section (loaded in one piece)
        placed = [(lib.codegen._engine.get_function_address(p[3]), p) for p in syms if p[2] == "T"]
        base = next((a - int(p[0], 16) for a, p in placed if a), None)
        if base is not None:
            rows += [(base + int(p[0], 16), int(p[1], 16), p[3], obj) for p in syms]
    SYMBOLS.write_text("".join(f"{a:x} {s:x} {n} {o}\n" for a, s, n, o in sorted(rows)))
    for _ in range(repeats):
        data = integrate(scene, keep=False)
    print(f"{name}: {repeats} runs, {data.solver['nfev']} RHS calls, "
          f"{data.solver['nsteps']} steps each", file=sys.stderr)


def _short(mangled: str) -> str:
    """``transient.core.stepper.advance`` from numba's mangled name."""
    parts, i = [], mangled.find("_ZN") + 3
    while i < len(mangled) and mangled[i].isdigit():
        j = i
        while mangled[j].isdigit():
            j += 1
        n = int(mangled[i:j])
        parts.append(mangled[j:j + n])
        i = j + n
    return ".".join(parts[-2:])


def _disassembly(obj: str, name: str, size: int) -> tuple[int, list[str]]:
    off = next(int(p[0], 16) for p in _text_symbols(Path(obj)) if p[3] == name)
    dis = subprocess.run(["objdump", "-dr", "--no-show-raw-insn", f"--start-address={off}",
                          f"--stop-address={off + size}", obj], capture_output=True,
                         text=True).stdout.splitlines()
    return off, dis


def report(calls_of: str | None = None) -> None:
    rows = [line.split() for line in SYMBOLS.read_text().splitlines()]
    starts = [int(r[0], 16) for r in rows]
    script = subprocess.run(["perf", "script", "-i", PERF_DATA, "-F", "ip"],
                            capture_output=True, text=True).stdout
    ips = [int(x, 16) for x in script.split()]
    by_fn = collections.defaultdict(collections.Counter)
    outside = 0
    for ip in ips:
        k = bisect.bisect_right(starts, ip) - 1
        if k >= 0 and ip < starts[k] + int(rows[k][1], 16):
            by_fn[k][ip - starts[k]] += 1
        else:
            outside += 1
    print(f"{len(ips)} samples, {outside} outside numba's code (libm's sincos, Python, ...)")
    print("share of all samples, of the function's samples on stack moves, function")
    total_moves = 0
    for k, hits in sorted(by_fn.items(), key=lambda kv: -sum(kv[1].values())):
        _, size, name, obj = rows[k]
        off, dis = _disassembly(obj, name, int(size, 16))
        moves, last_target, per_call, pending = 0, "?", collections.Counter(), 0
        for line in dis:
            reloc = re.search(r"R_X86_64_64\s+(\S+)", line)
            if reloc:
                last_target = reloc.group(1)
            m = re.match(r"\s*([0-9a-f]+):\s*(.*)", line)
            if not m:
                continue
            n = hits.get(int(m.group(1), 16) - off, 0)
            if STACK_MOVE.match(m.group(2)):
                moves += n
                pending += n
            if m.group(2).startswith("call"):
                per_call[_short(last_target) or last_target[:40]] += pending
                pending = 0
        total_moves += moves
        n_fn = sum(hits.values())
        share, moved = 100 * n_fn / len(ips), 100 * moves / max(n_fn, 1)
        print(f"{share:5.1f}%  {moved:5.1f}%  {_short(name)}")
        if calls_of and _short(name).endswith(calls_of):
            for target, n in per_call.most_common(12):
                print(f"{'':20s}{100 * n / len(ips):5.1f}% of all samples copying into {target}")
    print(f"stack moves: {100 * total_moves / len(ips):.1f}% of all samples")


if __name__ == "__main__":
    if sys.argv[1] == "run":
        run(sys.argv[2], *(int(a) for a in sys.argv[3:5]))
    else:
        report(sys.argv[3] if len(sys.argv) > 3 and sys.argv[2] == "--calls" else None)
