"""Layouts of the compiled code's flat arrays, declared once: named blocks laid end to end, their
offsets and sizes derived from the declaration instead of counted by hand.

numba indexes arrays without bounds checks, so a row or an index that two modules count
differently corrupts memory silently. Every flat array the kernels share — the state vector
(``model.layout.STATE``), the switches, the work array's rows, the stepper's settings and the
state it keeps between chunks (``stepper.io``), the rows of each reaction solver — is declared
here as a :class:`Layout`, and the integer constants the kernels index with are unpacked from it
(numba sees them as plain module-level integers, compiled in as constants):

    SETTINGS = Layout("settings", "rtol", "atol", ("grid", 4))
    C_RTOL, C_ATOL, C_GRID = SETTINGS       # 0, 1, 2; SETTINGS.size == 6

An unpacking that names more or fewer blocks than the layout holds fails at import. A block's
size is a number of entries known at import; a block whose length depends on the scene (per
cylinder, per pair, per shaft station) is declared with a :class:`Sized` rule instead, a formula
of the Model (:func:`transient.core.jit.formula`): the compiled code chains the rules in the
declared order (an offset is the one before it plus that block's size), and the Python side
runs the same rules (:meth:`Layout.offsets_for`). The blocks before the first sized one keep
offsets known at import (:meth:`Layout.fixed_offset`).

Pure Python; nothing here is compiled.
"""
from __future__ import annotations

from collections.abc import Callable, Iterator
from dataclasses import dataclass


@dataclass(frozen=True)
class Sized:
    """The length of a block that depends on the scene: ``rule`` of the object the layout is
    laid out for (the compiled Model; a formula, whose code the compiled code that indexes the
    array runs too), ``what`` says it in words (for the developer's tables)."""

    rule: Callable[[object], int]
    what: str


@dataclass(frozen=True)
class Block:
    """One named block of a layout: ``size`` entries (an int, or :class:`Sized`)."""

    name: str
    size: int | Sized = 1
    doc: str = ""


class Layout:
    """Named blocks laid end to end from ``start``, in the order given.

    Each block is a name (one entry), a ``(name, size)`` or ``(name, size, doc)`` tuple, or a
    :class:`Block`. Iterating yields each block's offset, in order (for unpacking into
    constants); :meth:`offset`, :meth:`size_of` and :attr:`end` give the rest. A layout with
    :class:`Sized` blocks has offsets known at import only up to its first sized block.
    """

    def __init__(self, name: str, *blocks, start: int = 0):
        self.name = name
        self.start = start
        self.blocks = tuple(_block(b) for b in blocks)
        names = [b.name for b in self.blocks]
        repeated = {n for n in names if names.count(n) > 1}
        if repeated:
            raise ValueError(f"layout {name}: blocks named twice: {sorted(repeated)}")
        for b in self.blocks:
            if isinstance(b.size, int) and b.size < 0:
                raise ValueError(f"layout {name}: block {b.name} has size {b.size}")
        self._index = {n: i for i, n in enumerate(names)}

    def __iter__(self) -> Iterator[int]:
        return iter(self.fixed_offset(b.name) for b in self.blocks)

    def __len__(self) -> int:
        return len(self.blocks)

    def __contains__(self, name: str) -> bool:
        return name in self._index

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(b.name for b in self.blocks)

    def index(self, name: str) -> int:
        """The block's number in the layout (its place, not its offset)."""
        try:
            return self._index[name]
        except KeyError:
            raise KeyError(f"layout {self.name} has no block {name!r}; it has "
                           f"{', '.join(self.names)}") from None

    def size_of(self, name: str) -> int:
        """The fixed size of block ``name``."""
        size = self.blocks[self.index(name)].size
        if isinstance(size, Sized):
            raise TypeError(f"layout {self.name}: block {name} is {size.what}, known per scene")
        return size

    def fixed_offset(self, name: str) -> int:
        """The offset of block ``name``, where every block before it has a fixed size."""
        offset = self.start
        for b in self.blocks[: self.index(name)]:
            if isinstance(b.size, Sized):
                raise TypeError(f"layout {self.name}: block {name} follows {b.name}, which is "
                                f"{b.size.what}: its offset is known per scene (offsets_for)")
            offset += b.size
        return offset

    offset = fixed_offset

    @property
    def end(self) -> int:
        """The offset just past the last block (all of fixed size)."""
        last = self.blocks[-1]
        return self.fixed_offset(last.name) + self.size_of(last.name)

    size = end

    def sizes_for(self, obj) -> list[int]:
        """Each block's size for ``obj`` (the Model its sized blocks' rules read; a rule that is
        a formula or a kernel runs as Python, its ``py_func``, the same code the compiled code
        runs)."""
        sizes = []
        for b in self.blocks:
            n = (getattr(b.size.rule, "py_func", b.size.rule)(obj) if isinstance(b.size, Sized)
                 else b.size)
            if int(n) != n or n < 0:
                raise ValueError(f"layout {self.name}: block {b.name} would have size {n!r}")
            sizes.append(int(n))
        return sizes

    def offsets_for(self, obj) -> list[int]:
        """The offset of every block for ``obj``, then the end: ``len(self) + 1`` integers."""
        offsets = [self.start]
        for n in self.sizes_for(obj):
            offsets.append(offsets[-1] + n)
        return offsets

    def table(self) -> list[tuple[str, str, str]]:
        """(name, offset or size rule, doc) of every block, for the developer's documentation."""
        rows = []
        offset: int | None = self.start
        for b in self.blocks:
            if isinstance(b.size, Sized):
                where = f"+{b.size.what}"
                offset = None
            else:
                where = (f"{offset}" if b.size == 1 else f"{offset}…{offset + b.size - 1}"
                         ) if offset is not None else f"+{b.size}"
                if offset is not None:
                    offset += b.size
            rows.append((b.name, where, b.doc))
        return rows


def _block(b) -> Block:
    if isinstance(b, Block):
        return b
    if isinstance(b, str):
        return Block(b)
    return Block(*b)


#: How a step's error control treats a state component (``layout.state_control``, the argument
#: ``control`` of :func:`transient.core.integrator.rk.error_norm`): the model declares it per
#: block of its state, the integrator reads it; neither imports the other.
#: NOT_CONTROLLED: no error test (a quadrature that does not feed back, a held value);
#: BY_SIZE: scaled by atol + rtol·|y|; BY_INCREMENT: scaled by atol + rtol·|Δy| over the step,
#: for a component that accumulates (φ, t: relative to its size, the error allowed would grow
#: with the run's length).
NOT_CONTROLLED, BY_SIZE, BY_INCREMENT = range(3)
