"""Input files read defensively: scenes, sweep files and tables are regular files of bounded size,
UTF-8 text without NUL bytes; a table's fields are numbers.

Every refusal is one :class:`~transient.errors.SceneError` that quotes at most the offending
token (:func:`~transient.errors.show_value`), never a line of the file.
"""
from __future__ import annotations

import csv
import math
import os
import re
import secrets
import stat
import tomllib
from pathlib import Path

import numpy as np

from ..errors import QUOTE_LIMIT, SceneError, clip, show_value

#: Largest scene, sweep or table file read [bytes]: a pressure table at 0.01° over a 4-stroke
#: cycle is ~1 MB, and a file far larger is a mistake (a log, a binary) that would only fill
#: the memory.
MAX_INPUT_BYTES = 16 * 2**20

#: Longest field of a table [characters]: a number or a column name is far shorter, and the
#: csv module refuses a field past its own limit with an exception of its own.
MAX_FIELD_CHARS = 200

#: What each kind of input file is, for its messages: (what it is, what to give instead, how to
#: save it as text).
KINDS = {
    "scene": ("a scene file", "a TOML file", "save the scene as UTF-8"),
    "sweep": ("a sweep file", "a TOML file", "save the sweep as UTF-8"),
    "table": ("a CSV file", "a CSV file", "save the table as UTF-8 CSV"),
}


def not_a_regular_file(path: Path) -> str:
    """What ``path`` is if it is there but not a regular file ("a folder", "a FIFO", …), else
    "": a FIFO or a device would be read forever, and a folder is no file to read."""
    try:
        mode = os.stat(path).st_mode  # (does not open it: a FIFO does not block here)
    except (OSError, ValueError):
        return ""
    for test, kind in ((stat.S_ISDIR, "a folder"), (stat.S_ISFIFO, "a FIFO"),
                       (stat.S_ISCHR, "a character device"), (stat.S_ISBLK, "a block device"),
                       (stat.S_ISSOCK, "a socket")):
        if test(mode):
            return kind
    return ""


def read_text(path: Path, kind: str) -> str:
    """The text of an input file of ``kind`` (:data:`KINDS`), or a SceneError keyed ``(file)``
    saying why it cannot be read: not a regular file, larger than :data:`MAX_INPUT_BYTES`, not
    UTF-8, or holding a NUL byte."""
    what, give, save = KINDS[kind]
    found = not_a_regular_file(path)
    if found:
        raise SceneError("(file)", f"is {found}, not {what}; give {give}", file=str(path))
    try:
        with open(path, "rb") as fh:
            data = fh.read(MAX_INPUT_BYTES + 1)  # (the size is read, not trusted from stat)
    except OSError as exc:
        raise SceneError("(file)", f"cannot read: {exc.strerror}", file=str(path)) from None
    except ValueError:  # (only a name holding a NUL byte gets here)
        raise SceneError("(file)", "cannot read: the name holds a NUL byte",
                         file=str(path)) from None
    if len(data) > MAX_INPUT_BYTES:
        raise SceneError("(file)", f"is larger than {MAX_INPUT_BYTES} bytes "
                                   f"({MAX_INPUT_BYTES // 2**20} MiB), the limit for {what}",
                         file=str(path))
    try:
        text = data.decode("utf-8-sig")  # (a byte-order mark is not part of the text)
    except UnicodeDecodeError as exc:
        raise SceneError("(file)", f"not UTF-8 text (byte {exc.start}); {save}",
                         file=str(path)) from None
    nul = text.find("\0")
    if nul >= 0:
        line = text.count("\n", 0, nul) + 1
        column = nul - text.rfind("\n", 0, nul)
        raise SceneError("(file)", f"holds a NUL byte (line {line}, column {column}); {what} "
                                   f"is text: {save}", file=str(path))
    return text


def parse_toml(text: str, file: str) -> dict:
    """``text`` parsed as TOML, or a SceneError keyed ``(syntax)``: tomllib's reason (a key it
    quotes cut to a token's length) and where, or that arrays or tables are nested too deeply.

    Long arrays of plain decimal numbers (a pressure or load table inline) are read by
    ``_numbers_apart``, not by tomllib, whose parser in Python takes some 35 µs a number:
    the same values, at a small part of the cost."""
    try:
        return _numbers_apart(text) or tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        reason, at, where = str(exc).partition(" (at ")
        raise SceneError("(syntax)", f"not valid TOML: {clip(reason, 2 * QUOTE_LIMIT)}{at}{where}",
                         file=file) from None
    except RecursionError:
        raise SceneError("(syntax)", "arrays or tables nested too deeply to read",
                         file=file) from None


#: Arrays of numbers longer than this [characters] are read apart from tomllib
#: (``_numbers_apart``): shorter ones cost it little.
LONG_ARRAY_CHARS = 2000
#: An array holding numbers, separators and TOML's whitespace only (no comment, no string, no
#: nested array): its content between the brackets.
_NUMBER_ARRAY = re.compile(rf"\[([0-9eE+\-., \t\r\n]{{{LONG_ARRAY_CHARS},}})\]")
def _numbers_apart(text: str) -> dict | None:
    """``text`` parsed as tomllib parses it, its long arrays of plain numbers read apart: each
    is replaced by a placeholder string, the numbers are converted as tomllib converts them
    (``int`` or ``float`` of each token), and the parsed placeholders are replaced by them. None
    when there is no such array, or when the placeholders did not all come back as whole values
    (an array inside a string or a comment) or the text does not parse: then tomllib reads the
    text as it is, and so decides every error and its position."""
    arrays: dict[str, list] = {}
    tag = f"\0{secrets.token_hex(8)}:"  # (no text holds it: a new one each time)

    def apart(match: re.Match) -> str:
        values = _plain_numbers(match.group(1))
        if values is None:
            return match.group(0)
        key = f"{tag}{len(arrays)}"
        arrays[key] = values
        return '"\\u0000' + key[1:] + '"'

    changed = _NUMBER_ARRAY.sub(apart, text)
    if not arrays:
        return None
    try:
        data = tomllib.loads(changed)
    except (tomllib.TOMLDecodeError, RecursionError):
        return None
    found: list[str] = []

    def restore(node):
        if isinstance(node, dict):
            return {k: restore(v) for k, v in node.items()}
        if isinstance(node, list):
            return [restore(v) for v in node]
        if isinstance(node, str) and node in arrays:
            found.append(node)
            return arrays[node]
        return node

    data = restore(data)
    return data if sorted(found) == sorted(arrays) else None


def _plain_numbers(content: str) -> list | None:
    """The numbers of an array's ``content`` (between its brackets) as tomllib gives them
    (``int`` of an integer's token, ``float`` of a float's), or None if it is not a list of
    plain TOML decimals (it is then left to tomllib). A token is one if ``int`` or ``float``
    reads it, as far as its characters go (``_NUMBER_ARRAY``: no underscore, no ``inf``) and
    :func:`_not_toml` finds nothing; no token may be empty but a last one (a trailing comma)."""
    if "\r" in content.replace("\r\n", "") or _not_toml(content):
        return None
    tokens = content.split(",")
    if not tokens[-1].strip(" \t\r\n"):
        tokens.pop()  # (a trailing comma, or none at all)
    try:
        return [float(t) if "." in t or "e" in t or "E" in t else int(t) for t in tokens]
    except ValueError:  # (an empty token, two numbers without a comma, a lone sign, …)
        return None


def _not_toml(content: str) -> bool:
    """Whether ``content`` (of ``_NUMBER_ARRAY``'s characters) holds what Python's ``int`` and
    ``float`` read but TOML does not: a number with a leading zero (``01``, ``-00.5``; an
    exponent may have them) or a dot without a digit on both sides (``1.``, ``.5``). One pass
    over the characters in numpy: a regular expression with look-behinds takes longer than
    reading the numbers."""
    b = np.frombuffer(content.encode("ascii"), dtype=np.uint8)
    digit = (b >= ord("0")) & (b <= ord("9"))
    before = np.concatenate([[ord(",")], b[:-1]])  # (the start counts as a separator)
    twice = np.concatenate([[ord(",")], before[:-1]])
    sign = (before == ord("+")) | (before == ord("-"))
    exponent = (twice == ord("e")) | (twice == ord("E"))
    separator = ((before == ord(",")) | (before == ord(" ")) | (before == ord("\t"))
                 | (before == ord("\n")) | (before == ord("\r")))
    after_digit = np.append(digit[1:], False)
    before_digit = np.concatenate([[False], digit[:-1]])
    zero = (b == ord("0")) & after_digit & (separator | (sign & ~exponent))
    dot = (b == ord(".")) & ~(before_digit & after_digit)
    return bool(np.any(zero | dot))


def table_rows(text: str) -> list[tuple[int, list[str]]]:
    """The rows of a CSV table as (line number, fields), comment (``#``) and blank lines left
    out; a malformed line is a SceneError keyed ``(line)`` for the caller to place."""
    rows = []
    for number, line in enumerate(text.splitlines(), start=1):
        if not line.strip() or line.lstrip().startswith("#"):
            continue
        longest = max(len(field) for field in line.split(","))
        if longest > MAX_FIELD_CHARS:
            raise SceneError("(line)", f"line {number} holds a field of {longest} characters; "
                                       f"a table's fields are numbers and column names (at most "
                                       f"{MAX_FIELD_CHARS} characters)")
        try:
            rows.append((number, next(csv.reader([line]))))
        except csv.Error as exc:
            raise SceneError("(line)", f"line {number}: not CSV ({exc})") from None
    return rows


def table_number(text: str, number: int, column: str) -> float:
    """The field ``text`` of line ``number`` in ``column`` as a finite number, else a SceneError
    keyed ``(line)`` quoting the field (cut to a token's length)."""
    try:
        value = float(text)
    except ValueError:
        raise SceneError("(line)", f"line {number}, column {column}: {show_value(text.strip())} "
                                   f"is not a number") from None
    if not math.isfinite(value):
        raise SceneError("(line)", f"line {number}, column {column}: {show_value(text.strip())} "
                                   f"is not finite; give finite numbers") from None
    return value
