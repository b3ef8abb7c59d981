"""Signatures of the extension's functions, read from the first lines of their docstrings.

pybind11 writes each function's signature as the first line of its docstring (one numbered line
an overload), but CPython's `inspect.signature` cannot see it on a built-in function. `attach`
wraps every public function and method of the extension in a plain Python function that carries
its parsed `__signature__` (and gives every class the signature of its constructor), so that
`inspect.signature`, `help` and editors that introspect see parameter names, defaults and types.
Overloaded functions keep the signature `(*args, **kwargs)`; their overloads are in the stubs.
scripts/make_stubs.py writes the type stubs (*.pyi) from the same parse.
"""

import functools
import inspect
import re

_SIGNATURE = re.compile(r"^(?P<name>\w+)\((?P<params>.*)\)(?: -> (?P<returns>.+))?$")


class Default:
    """A default value as pybind11 printed it: its repr is that text (e.g. `inf`, `(0, 0, 0)`)."""

    def __init__(self, text):
        self.text = text

    def __repr__(self):
        return self.text


class Parsed:
    """One signature: parameters as (name, annotation, default text or None, kind)."""

    def __init__(self, params, returns, doc):
        self.params = params
        self.returns = returns
        self.doc = doc


def split_top_level(text, separator=","):
    """Splits at separators outside brackets, parentheses and quotes."""
    parts, depth, quote, current = [], 0, None, []
    for char in text:
        if quote:
            current.append(char)
            if char == quote:
                quote = None
            continue
        if char in "'\"":
            quote = char
        elif char in "([{":
            depth += 1
        elif char in ")]}":
            depth -= 1
        elif char == separator and depth == 0:
            parts.append("".join(current).strip())
            current = []
            continue
        current.append(char)
    if "".join(current).strip():
        parts.append("".join(current).strip())
    return parts


def parse_line(line):
    """Parses `name(a: T, b: U = d, *, c: V = e) -> R`; None when the line is not one."""
    match = _SIGNATURE.match(line.strip())
    if not match:
        return None
    params, kind = [], inspect.Parameter.POSITIONAL_OR_KEYWORD
    for part in split_top_level(match.group("params")):
        if part == "*":
            kind = inspect.Parameter.KEYWORD_ONLY
            continue
        if part.startswith("**"):
            params.append((part[2:].split(":")[0].strip(), None, None, inspect.Parameter.VAR_KEYWORD))
            continue
        if part.startswith("*"):
            params.append((part[1:].split(":")[0].strip(), None, None, inspect.Parameter.VAR_POSITIONAL))
            kind = inspect.Parameter.KEYWORD_ONLY
            continue
        default = None
        pieces = split_top_level(part, "=")
        if len(pieces) == 2:
            part, default = pieces[0].strip(), pieces[1].strip()
        name, _, annotation = part.partition(":")
        params.append((name.strip(), annotation.strip() or None, default, kind))
    return match.group("name"), Parsed(params, match.group("returns"), "")


def parse(doc):
    """The signatures a pybind11 docstring gives: a list (several for an overloaded function)."""
    if not doc:
        return []
    lines = doc.split("\n")
    first = parse_line(lines[0])
    if first is None:
        return []
    if len(lines) > 1 and lines[1].strip() == "Overloaded function.":
        overloads, current = [], None
        for line in lines[2:]:
            numbered = re.match(r"^\d+\. (.*)$", line)
            parsed = parse_line(numbered.group(1)) if numbered else None
            if parsed:
                current = parsed[1]
                overloads.append(current)
            elif current is not None:
                current.doc += line + "\n"
        for overload in overloads:
            overload.doc = overload.doc.strip()
        return overloads
    first[1].doc = "\n".join(lines[1:]).strip()
    return [first[1]]


def signature(parsed, drop_self=False):
    """An inspect.Signature (annotations and defaults as pybind11 printed them)."""
    params = parsed.params[1:] if drop_self and parsed.params else parsed.params
    return inspect.Signature(
        [
            inspect.Parameter(
                name,
                kind,
                default=inspect.Parameter.empty if default is None else Default(default),
                annotation=inspect.Parameter.empty if annotation is None else annotation,
            )
            for name, annotation, default, kind in params
        ],
        return_annotation=parsed.returns or inspect.Signature.empty,
    )


def _wrap(function, parsed, method=False):
    @functools.wraps(function)
    def wrapper(*args, **kwargs):
        return function(*args, **kwargs)

    wrapper.__signature__ = signature(parsed)
    if method:
        # The first parameter, `self: delta.Mesh`, is the instance.
        params = list(wrapper.__signature__.parameters.values())
        if params:
            params[0] = params[0].replace(annotation=inspect.Parameter.empty, name="self")
            wrapper.__signature__ = wrapper.__signature__.replace(parameters=params)
    return wrapper


def _is_builtin(value):
    return type(value).__name__ in ("builtin_function_or_method", "instancemethod")


def attach(module):
    """Gives the public functions and classes of the extension module `module` signatures."""
    for name, value in list(vars(module).items()):
        if name.startswith("_"):
            continue
        if _is_builtin(value):
            parsed = parse(value.__doc__)
            if len(parsed) == 1:
                setattr(module, name, _wrap(value, parsed[0]))
        elif isinstance(value, type) and value.__module__.startswith("delta"):
            _attach_class(value)


def _attach_class(cls):
    for name, value in list(vars(cls).items()):
        if name.startswith("__") and name != "__init__":
            continue
        if isinstance(value, staticmethod):
            parsed = parse(value.__func__.__doc__)
            if len(parsed) == 1:
                setattr(cls, name, staticmethod(_wrap(value.__func__, parsed[0])))
        elif _is_builtin(value):
            parsed = parse(value.__doc__)
            if name == "__init__":
                if len(parsed) == 1:
                    cls.__signature__ = signature(parsed[0], drop_self=True).replace(
                        return_annotation=inspect.Signature.empty
                    )
            elif len(parsed) == 1:
                setattr(cls, name, _wrap(value, parsed[0], method=True))
