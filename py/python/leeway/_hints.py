"""Messages of the native half in Python's spelling. The Rust libraries
word their errors, warnings and notes for the command line (``--centring
none``, ``--resample H``, ``leeway check --json``); a Python user passes
keywords. Every CLI flag such a message may name is mapped here, once, to
the keyword of the Python API and how its value is written, and every text
that reaches a Python user (exception messages and hints, warnings, the
``warnings``/``notes`` lists) goes through :func:`python_spelling`.
``py/tests/test_hints.py`` checks that every flag named in the Rust sources
is mapped, so a new one cannot leak through."""

from __future__ import annotations

import re

# flag → (keyword, how a value is written): "text" quotes a choice
# (`centring="none"`), "number" writes it as is (`resample=H`), "flag" is a
# switch (`aggregate=True`), "off" a switch that turns something off
# (`runaway_guard=False`), "mapping" a dict (`nominal={name: value}`),
# "name" a keyword that takes no written value here (`data`).
KEYWORDS: dict[str, tuple[str, str]] = {
    "--method": ("method", "text"),
    "--instruments": ("instruments", "text"),
    "--initial": ("initial", "text"),
    "--centring": ("centring", "text"),
    "--combine": ("combine", "text"),
    "--resample": ("resample", "number"),
    "--max-gap": ("max_gap", "number"),
    "--keep": ("keep", "name"),
    "--step": ("step", "number"),
    "--time-tolerance": ("time_tolerance", "number"),
    "--lags": ("lags", "number"),
    "--tolerance": ("tolerance", "number"),
    "--validate": ("validate", "name"),
    "--max-refinements": ("max_refinements", "number"),
    "--refine-subsample": ("refine_subsample", "number"),
    "--nominal": ("nominal", "mapping"),
    "--disturbance": ("disturbances", "mapping"),
    "--x0": ("x0", "mapping"),
    "--disturbance-std": ("disturbance_std", "mapping"),
    "--correlation-time": ("correlation_time", "mapping"),
    "--noise": ("noise", "mapping"),
    "--seed": ("seed", "number"),
    "--aggregate": ("aggregate", "flag"),
    "--strict": ("strict", "flag"),
    "--no-runaway-guard": ("runaway_guard", "off"),
    "--pattern": ("patterns", "name"),
    "--data": ("data", "name"),
    "--params": ("theta", "name"),
    "--input": ("inputs", "name"),
    "--json": ("", "name"),
    "--verbose": ("", "name"),
}

# The choices of the "text" options (estimate/src/method.rs, the IR's centring).
CHOICES = {
    "method": {"ls", "iv1", "iv2", "iv3"},
    "instruments": {"simulated", "delayed"},
    "initial": {"nominal", "delayed"},
    "centring": {"experiment", "pooled", "none"},
    "combine": {"summed", "stacked"},
}

# The commands, as the Python calls that do their work.
COMMANDS = {
    "check": "Model.check",
    "estimate": "leeway.estimate",
    "simulate": "leeway.simulate",
    "validate": "leeway.validate",
    "select": "Model.select",
}

_FLAG = re.compile(
    r"(?:leeway (?P<command>check|estimate|simulate|validate|select) )?"
    r"(?P<flag>--[a-z][a-z0-9-]*)"
    r"(?: (?P<value>[A-Za-z0-9_.+-]+|\{[^}]*\}))?"
)


def _value(keyword: str, kind: str, value: str | None) -> tuple[str, bool]:
    """The keyword with its value, and whether the value was consumed."""
    if kind == "text" and value in CHOICES.get(keyword, ()):
        return f'{keyword}="{value}"', True
    if kind == "number" and value is not None and re.fullmatch(r"[A-Z]+|[-+0-9.eE]+|\{[^}]*\}", value):
        return f"{keyword}={value}", True
    if kind == "mapping" and value is not None and re.fullmatch(r"[A-Z.]+|NAME=VALUE.*", value):
        return f"{keyword}={{name: value}}", True
    if kind == "flag":
        return f"{keyword}=True", False
    if kind == "off":
        return f"{keyword}=False", False
    return (f"{keyword}=…" if kind in ("text", "number") else keyword), False


def _replace(m: re.Match[str]) -> str:
    flag, value, command = m.group("flag"), m.group("value"), m.group("command")
    if flag not in KEYWORDS:
        return m.group(0)
    keyword, kind = KEYWORDS[flag]
    if flag == "--verbose":
        # The text output's detail line: in Python, the warnings' full text.
        return "Estimate.warnings"
    if flag == "--json":
        # `leeway check --json` lists everything: in Python, the Check it returns.
        return f"{COMMANDS[command]}()" if command else "the JSON document"
    text, consumed = _value(keyword, kind, value)
    rest = "" if consumed or value is None else f" {value}"
    if command:
        return f"{COMMANDS[command]}({text}){rest}"
    return text + rest


def python_spelling(text: str) -> str:
    """``text`` with every CLI flag it names written as the Python keyword
    (``--centring none`` → ``centring="none"``, ``--resample H`` →
    ``resample=H``, ``--aggregate`` → ``aggregate=True``, ``leeway check
    --json`` → ``Model.check()``)."""
    if "--" not in text:
        return text
    return _FLAG.sub(_replace, text)
