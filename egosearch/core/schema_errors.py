"""A jsonschema ``ValidationError`` as one line that names what is allowed, where jsonschema's own words
do not: a value that fits none of an ``anyOf``'s branches ("is not valid under any of the given schemas")
is told each branch, and an unknown key ("Additional properties are not allowed") the keys allowed there.
The workflow config (egosearch.workflow.check) and the variant files (egosearch.variants) both use it."""

from __future__ import annotations

import difflib
import re

_KINDS = {"integer": "an integer", "number": "a number", "string": "a string", "boolean": "true or false",
          "object": "a mapping", "array": "a list", "null": "nothing"}


def allowed_words(schema: dict) -> str:
    """What one schema branch allows, in words: ``'auto'``, ``an integer from 1 to 64``."""
    if "const" in schema:
        return repr(schema["const"])
    if "enum" in schema:
        return "one of " + ", ".join(repr(v) for v in schema["enum"])
    kind = schema.get("type")
    words = " or ".join(_KINDS.get(k, k) for k in kind) if isinstance(kind, list) else _KINDS.get(kind, "a value")
    low, high = schema.get("minimum"), schema.get("maximum")
    if low is not None and high is not None:
        return f"{words} from {low} to {high}"
    if low is not None:
        return f"{words} >= {low}"
    if high is not None:
        return f"{words} <= {high}"
    return words


def _branching(err):
    """The ``anyOf``/``oneOf`` error that ``err`` is (or that jsonschema's best match descended from), or None."""
    while err is not None:
        if err.validator in ("anyOf", "oneOf"):
            return err
        err = err.parent
    return None


def schema_error(err) -> tuple[str, str]:
    """(where, what): the key path of a ``jsonschema.ValidationError`` ("(top level)" at the top) and its
    message, with the allowed values or keys named."""
    branching = _branching(err)
    if branching is not None:
        where = "/".join(str(p) for p in branching.absolute_path) or "(top level)"
        branches = branching.validator_value
        allowed = " or ".join(allowed_words(b) for b in branches)
        value = branching.instance
        near = [b["const"] for b in branches if isinstance(b.get("const"), str) and isinstance(value, str)
                and b["const"].lower() == value.strip().lower()]
        hint = f" (did you mean {near[0]!r}?)" if near else ""
        return where, f"{value!r} is not allowed{hint}; allowed: {allowed}"
    where = "/".join(str(p) for p in err.absolute_path) or "(top level)"
    if err.validator == "additionalProperties" and err.validator_value is False and isinstance(err.instance, dict):
        known = list(err.schema.get("properties", {}))
        patterns = list(err.schema.get("patternProperties", {}))
        extra = [key for key in err.instance
                 if key not in known and not any(re.search(p, str(key)) for p in patterns)]
        if extra and known:
            named = []
            for key in extra:
                near = difflib.get_close_matches(str(key), known, n=1)
                named.append(f"{key!r}" + (f" (did you mean {near[0]!r}?)" if near else ""))
            verb = "is not a key here" if len(named) == 1 else "are not keys here"
            return where, f"{', '.join(named)} {verb}; allowed: {', '.join(known)}"
    return where, err.message
