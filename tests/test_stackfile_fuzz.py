"""Fuzzing the stack-file reader: random TOML documents and near-misses of the files in examples/.

The contract (issue 16): `load_stack_file` either succeeds or raises a `HertzChainError` (normally a
`StackFileError`) whose message is one line; never another exception, a traceback, a RuntimeWarning or
a hang. Near-misses drop a key, misspell one, or replace a value by a wrong type, a wrong unit, a
negative, huge or NaN-ish value.
"""

from __future__ import annotations

import math
import tomllib
import warnings
from pathlib import Path

import pytest
import tomli_w
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from hertz_chain.errors import HertzChainError
from hertz_chain.stackfile import load_stack_file, parse_stack

EXAMPLES = sorted((Path(__file__).resolve().parents[1] / "examples").glob("*.toml"))
DOCS = {p.name: tomllib.loads(p.read_text(encoding="utf-8")) for p in EXAMPLES}
FUZZ = settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow,
                                                                        HealthCheck.function_scoped_fixture])


def check(load) -> None:
    """Run `load()`: success, or a one-line HertzChainError; no RuntimeWarning either way."""
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        try:
            load()
        except HertzChainError as exc:
            message = str(exc)
            assert message and "\n" not in message and "\r" not in message, message


def leaves(node, path=()):
    """Every (path, value) of a parsed document, tables and lists included."""
    yield path, node
    if isinstance(node, dict):
        for k, v in node.items():
            yield from leaves(v, path + (k,))
    elif isinstance(node, list):
        for i, v in enumerate(node):
            yield from leaves(v, path + (i,))


def replaced(doc, path, value):
    import copy

    doc = copy.deepcopy(doc)
    node = doc
    for p in path[:-1]:
        node = node[p]
    if value is _DROP:
        if isinstance(node, list):
            node.pop(path[-1])
        else:
            node.pop(path[-1])
    else:
        node[path[-1]] = value
    return doc


_DROP = object()
BAD_VALUES = st.sampled_from([
    _DROP, -1, 0, -0.0, 1e308, -1e308, 1e-308, 2**63 - 1, 10**30, math.inf, -math.inf, math.nan, True, "",
    "nan", "inf kg", "-1 m", "1 kg", "1 s", "1e9 N/m", "10**400 kg", "10**10**10 m", "9^9^9 s", "1/0",
    "1e400 m/s", "x" * 300, "1 parsec", "1 c", "0.8 m", "optimal", "tsuji", [], [1], [[1]], {}, {"a": 1},
])


def misspell(key: str, how: int) -> str:
    if not key:
        return "x"
    how %= 3
    if how == 0:
        return key[:-1]
    if how == 1:
        return key + "s"
    return key.replace("_", "") if "_" in key else key.upper()


@FUZZ
@given(name=st.sampled_from(sorted(DOCS)), data=st.data(), value=BAD_VALUES)
def test_near_misses_of_the_examples(name, data, value):
    doc = DOCS[name]
    paths = [p for p, _ in leaves(doc) if p]
    path = data.draw(st.sampled_from(paths))
    check(lambda: parse_stack(replaced(doc, path, value)))


@FUZZ
@given(name=st.sampled_from(sorted(DOCS)), data=st.data(), how=st.integers(0, 2))
def test_misspelt_keys_of_the_examples(name, data, how):
    import copy

    doc = copy.deepcopy(DOCS[name])
    paths = [p for p, v in leaves(doc) if p and isinstance(p[-1], str)]
    path = data.draw(st.sampled_from(paths))
    node = doc
    for p in path[:-1]:
        node = node[p]
    node[misspell(path[-1], how)] = node.pop(path[-1])
    check(lambda: parse_stack(doc))


KEYS = st.sampled_from(["drop", "stack", "contact", "solver", "ground", "materials", "masses", "gaps",
                        "law", "stiffness", "restitution", "impact_velocity", "height", "gravity", "n",
                        "design", "kind", "max_steps", "n_output", "dt_output", "t_max", "index",
                        "interface", "radius", "shape", "material", "velocities", "title", "x"])
SCALARS = st.one_of(
    st.integers(min_value=-(2**63), max_value=2**63 - 1),
    st.floats(allow_nan=True, allow_infinity=True),
    st.booleans(),
    st.text(max_size=20),
    st.sampled_from(["1 kg", "1 cm", "1 m/s", "1e9 N/m^1.5", "0.8", "tsuji", "hertz", "mvg", "optimal"]),
)
VALUES = st.recursive(SCALARS, lambda inner: st.one_of(st.lists(inner, max_size=4),
                                                       st.dictionaries(KEYS, inner, max_size=4)), max_leaves=12)


@FUZZ
@given(doc=st.dictionaries(KEYS, VALUES, max_size=6))
def test_random_documents(doc, tmp_path_factory):
    try:
        text = tomli_w.dumps(doc)
    except (TypeError, ValueError):  # not representable in TOML (e.g. a list of tables and scalars)
        return
    path = tmp_path_factory.mktemp("fuzz") / "doc.toml"
    path.write_text(text, encoding="utf-8")
    check(lambda: load_stack_file(path))


@FUZZ
@given(text=st.text(max_size=300))
def test_random_text(text):
    check(lambda: parse_stack(text))


@pytest.mark.parametrize("path", EXAMPLES, ids=[p.name for p in EXAMPLES])
def test_the_examples_still_load(path):
    assert load_stack_file(path).stack is not None
