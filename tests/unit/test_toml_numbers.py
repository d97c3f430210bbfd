"""Long inline arrays of numbers read beside tomllib (``scene.files._numbers_apart``): the parsed
document must be tomllib's own, value for value and type for type, whatever the text; where the
fast reading cannot vouch for that (an array in a string or a comment, a token TOML does not
allow), tomllib reads the text as it is and so gives every error and its position."""
from __future__ import annotations

import random
import tomllib

import pytest

from transient.errors import SceneError
from transient.scene import files
from transient.scene.files import LONG_ARRAY_CHARS, parse_toml

N = LONG_ARRAY_CHARS // 4  # (numbers enough for an array past the threshold)


def numbers(seed: int, n: int = N) -> list[str]:
    """TOML tokens of integers and floats in every form TOML allows them."""
    rng = random.Random(seed)
    forms = [lambda: str(rng.randint(-10**6, 10**6)), lambda: f"{rng.uniform(-1e3, 1e3)!r}",
             lambda: f"{rng.uniform(0, 1):.6e}", lambda: f"+{rng.randint(0, 99)}",
             lambda: f"{rng.randint(1, 9)}E-0{rng.randint(1, 9)}", lambda: "-0.0",
             lambda: f"{rng.randint(1, 9)}.{rng.randint(0, 9)}e+{rng.randint(0, 300)}",
             lambda: "0", lambda: f"{10**rng.randint(20, 40)}"]
    return [rng.choice(forms)() for _ in range(n)]


def same(a, b) -> bool:
    """Equal, with the same types all the way down (1 and 1.0 are not the same)."""
    if type(a) is not type(b):
        return False
    if isinstance(a, dict):
        return a.keys() == b.keys() and all(same(a[k], b[k]) for k in a)
    if isinstance(a, list):
        return len(a) == len(b) and all(same(x, y) for x, y in zip(a, b))
    return a == b or (a != a and b != b)


def documents() -> dict[str, str]:
    row = ", ".join(numbers(1))
    lines = ",\n    ".join(numbers(2))
    return {
        "one-line": f"[gas]\nmodel = \"table\"\nphi = [{row}]\np = [{row}]\n",
        "multi-line-trailing-comma": f"x = [\n    {lines},\n]\n",
        "crlf": f"x = [\r\n{', '.join(numbers(3))}\r\n]\r\ny = 1\r\n",
        "inline-table": f"t = {{a = [{row}], b = \"s\"}}\n",
        "array-of-tables": f"[[pairs]]\nspeed = [{row}]\n[[pairs]]\nspeed = [1, 2]\n",
        "nested-rows": f"m = [[{row}], [{', '.join(numbers(4))}]]\n",
        "beside-strings": f"s = \"[1, 2]\"\nx = [{row}] # a comment [3]\nu = '[{row}]'\n",
        # TOML numbers the fast reading leaves to tomllib, in a long array
        "other-forms": f"x = [{row}, 0x10, 0o7, 0b1, 1_000, inf, -nan, 6.626e-34]\n",
    }


@pytest.mark.parametrize("name, text", list(documents().items()))
def test_long_arrays_parse_as_tomllib_parses_them(name, text):
    assert same(parse_toml(text, "t.toml"), tomllib.loads(text))


def test_the_long_arrays_do_not_reach_tomllib(monkeypatch):
    """The point of the fast reading: tomllib sees the document without its long arrays."""
    seen = []
    loads = tomllib.loads
    monkeypatch.setattr(files.tomllib, "loads", lambda text: seen.append(text) or loads(text))
    text = documents()["one-line"]
    parse_toml(text, "t.toml")
    assert len(seen) == 1 and len(seen[0]) < LONG_ARRAY_CHARS < len(text)


@pytest.mark.parametrize("text", [
    "s = \"\"\"\n[" + ", ".join(numbers(5)) + "]\n\"\"\"\n",  # in a multi-line string
    "s = '''[" + ", ".join(numbers(5)) + "]'''\n",  # in a literal multi-line string
    "# [" + ", ".join(numbers(5)) + "]\nx = 1\n",  # in a comment
])
def test_an_array_inside_a_string_or_a_comment_is_left_to_tomllib(text):
    assert same(parse_toml(text, "t.toml"), tomllib.loads(text))


@pytest.mark.parametrize("bad", ["01", "1.", ".5", "1e", "- 1", "1__0", "0b2", "1 2", ""])
def test_a_token_toml_does_not_allow_gives_tomllibs_error(bad):
    tokens = numbers(6)
    tokens[len(tokens) // 2] = bad
    text = "a = 1\nx = [" + ", ".join(tokens) + "]\n"
    with pytest.raises(tomllib.TOMLDecodeError) as want:
        tomllib.loads(text)
    with pytest.raises(SceneError) as got:
        parse_toml(text, "t.toml")
    assert got.value.message.endswith(str(want.value).partition(" (at ")[2][:-1] + ")")


def test_short_token_strings_read_as_tomllib_reads_them_or_not_at_all():
    """Every string of up to 9 characters of the array's alphabet (random, seeded): the fast
    reading returns None (tomllib decides) or exactly tomllib's values and types."""
    rng = random.Random(7)
    alphabet = "0123456789eE+-. ,\t\n\r"
    taken = 0
    for _ in range(20000):
        content = "".join(rng.choice(alphabet) for _ in range(rng.randint(0, 9)))
        got = files._plain_numbers(content)
        if got is None:
            continue
        taken += 1
        assert same(got, tomllib.loads(f"a = [{content}]")["a"]), repr(content)
    assert taken > 1000  # (the alphabet reads as numbers often enough to test something)
