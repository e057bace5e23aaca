"""Reading a YAML file safely and naming its problems (profiles and line files).

No aliases or anchors, bounded size and nesting, one line per problem ``FILE:LINE: FIELD = VALUE: RULE``, and
the path of a pydantic error resolved against the document (union branches pydantic inserts left out).
"""

from __future__ import annotations

import re
from typing import Any

from .errors import ProfileError


#: a profile is a few kilobytes; anything larger than this is refused before it is parsed [bytes]
PROFILE_MAX_BYTES = 1 << 20
#: deepest nesting of mappings and sequences a profile may have (the real ones use 5)
PROFILE_MAX_DEPTH = 32


#: a float in exponent form as YAML 1.2 writes it, which YAML 1.1 (PyYAML) reads as text
EXPONENT_TAG = "tag:pickplace,2026:exponent-number"
EXPONENT_FLOAT = re.compile(r"^[-+]?(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)[eE][-+]?[0-9]+$")


def _safe_loader(text: str, source: str, what: str = "profile"):
    """A yaml.SafeLoader that refuses aliases and anchors (a recursive alias or a "billion laughs" profile
    must not exhaust the stack or the memory) and nesting deeper than ``PROFILE_MAX_DEPTH``, each with one
    line naming the file, the line and the rule. ``what`` names the kind of file in the messages (a line file
    is read the same way)."""
    import yaml

    class Loader(yaml.SafeLoader):
        depth = 0

        def compose_node(self, parent, index):  # noqa: ANN001 - PyYAML's signature
            if self.check_event(yaml.AliasEvent):
                ev = self.peek_event()
                raise ProfileError(f"{source}:{ev.start_mark.line + 1}: YAML alias *{ev.anchor} is not allowed in a "
                                   f"{what} (write the value out; aliases can expand without bound)")
            ev = self.peek_event()
            if getattr(ev, "anchor", None):
                raise ProfileError(f"{source}:{ev.start_mark.line + 1}: YAML anchor &{ev.anchor} is not allowed in a "
                                   f"{what} (write the value out; aliases can expand without bound)")
            self.depth += 1
            try:
                if self.depth > PROFILE_MAX_DEPTH:
                    raise ProfileError(f"{source}:{ev.start_mark.line + 1}: nested deeper than {PROFILE_MAX_DEPTH} "
                                       f"levels (a {what} needs {'5' if what == 'profile' else 'at most 8'})")
                return super().compose_node(parent, index)
            finally:
                self.depth -= 1

    # a number in exponent form without a dot or an exponent sign (5e-2, 15e-5, 4.18e2, 1E6) is a float in YAML 1.2,
    # but text to PyYAML's YAML 1.1 rules, which a number field then refused as "a number in quotes": kept as text
    # that a number field reads as the number, and a text field (a name 1e5) as written
    from .numbers import ExponentNumber

    Loader.add_implicit_resolver(EXPONENT_TAG, EXPONENT_FLOAT, list("-+0123456789."))
    Loader.add_constructor(EXPONENT_TAG, lambda loader, node: ExponentNumber(loader.construct_scalar(node)))
    return Loader(text)


def _yaml_with_lines(text: str, source: str, what: str = "profile") -> tuple[Any, dict[tuple, int]]:
    """Parse YAML; return the data and a map from each value's path (keys/indices) to its 1-based line
    (``what``: the kind of file, for the messages)."""
    import yaml

    if len(text) > PROFILE_MAX_BYTES:
        raise ProfileError(f"{source}: {len(text)} characters; a {what} may have at most {PROFILE_MAX_BYTES} "
                           "(1 MiB): is this the right file?")
    loader = None
    try:
        loader = _safe_loader(text, source, what)  # (its reader refuses control characters at once: inside the try)
        node = loader.get_single_node()
        if node is None:
            return None, {}
        data = loader.construct_document(node)
    except yaml.YAMLError as exc:
        raise ProfileError(_yaml_problem(exc, text, source)) from None
    except ValueError:  # an integer longer than Python converts from text (4300 digits)
        line = next((n.start_mark.line + 1 for n in _scalars(node) if len(str(n.value)) > 4000), None)
        raise ProfileError(f"{source}:{line}: a number of more than 4000 digits: not a value a {what} can "
                           "have") from None
    finally:
        if loader is not None:
            loader.dispose()
    lines: dict[tuple, int] = {}

    def walk(n: Any, path: tuple) -> None:
        lines[path] = n.start_mark.line + 1
        if isinstance(n, yaml.MappingNode):
            seen: dict[Any, int] = {}
            for k, v in n.value:
                key = k.value
                if key in seen:
                    raise ProfileError(
                        f"{source}:{k.start_mark.line + 1}: duplicate key {key!r} (first at line {seen[key]})"
                    )
                seen[key] = k.start_mark.line + 1
                walk(v, path + (key,))
        elif isinstance(n, yaml.SequenceNode):
            for i, v in enumerate(n.value):
                walk(v, path + (i,))

    walk(node, ())
    return data, lines


def _scalars(node: Any):
    """Every scalar node under ``node`` (YAML's node tree), in document order."""
    import yaml

    if isinstance(node, yaml.ScalarNode):
        yield node
    elif isinstance(node, yaml.MappingNode):
        for k, v in node.value:
            yield from _scalars(k)
            yield from _scalars(v)
    elif isinstance(node, yaml.SequenceNode):
        for v in node.value:
            yield from _scalars(v)


def _yaml_problem(exc, text: str, source: str) -> str:
    """One line for a YAML error: ``FILE:LINE: not valid YAML: PROBLEM``; a character YAML does not allow (a control
    character such as VT, FF or BEL, U+FFFE) is named by its code and line."""
    mark = getattr(exc, "problem_mark", None)
    line = mark.line + 1 if mark else None
    position = getattr(exc, "position", None)  # a ReaderError: the character's offset in the text
    if line is None and isinstance(position, int):
        line = text.count("\n", 0, position) + 1
    where = f"{source}:{line}" if line else source
    character = getattr(exc, "character", None)
    if isinstance(character, (str, int)) and position is not None:
        code = ord(character) if isinstance(character, str) else character
        return (f"{where}: not valid YAML: the character U+{code:04X} is not allowed in YAML text (a control character "
                "or a non-character: delete it)")
    problem = getattr(exc, "problem", None) or str(exc).splitlines()[0]
    return f"{where}: not valid YAML: {problem}"


_ABSENT = object()  # a key or tuple element the document does not have


def _resolve(loc: tuple, data: Any, kind: str = "") -> tuple[list, Any, int | None]:
    """(real path, the value there or _ABSENT, index in loc of the last (innermost) union tag or None).

    pydantic puts union branch names (``JointSpec``, ``list[JointSpec]``) and the discriminator tag
    (``scara``) into ``loc``; only parts that are keys or indices of the document are kept. A key missing
    from a mapping (``kind`` "missing" or "extra_forbidden": the last part of ``loc`` is a key), or an index
    past the end of a list (a tuple that is too short), ends the path."""
    names_key = kind in ("missing", "extra_forbidden")
    real: list = []
    node: Any = data
    tag: int | None = None
    loc = list(loc)
    for n, part in enumerate(loc):
        last = n == len(loc) - 1
        if isinstance(node, dict) and part in node:
            real.append(part)
            node = node[part]
        elif isinstance(node, (list, tuple)) and isinstance(part, int) and 0 <= part < len(node):
            real.append(part)
            node = node[part]
        elif last and names_key and isinstance(node, dict):
            real.append(part)  # a missing or unknown key: name it
            node = _ABSENT
        elif last and names_key and isinstance(node, (list, tuple)) and isinstance(part, int):
            real.append(part)  # an element a fixed-length list lacks
            node = _ABSENT
        else:
            tag = n  # a union branch / discriminator tag pydantic inserted; not a key of the document
    return real, node, tag


def _prune_union_branches(errors: list[dict], data: Any) -> list[dict]:
    """Of the errors a union produced (one set per branch it tried), keep the branch that got furthest
    into the document: for ``joints: [ {...} ]`` the list branch's own problem, not "should be a mapping"
    from the single-spec branch."""
    best: dict[tuple, tuple[int, Any]] = {}  # union site → (depth, branch tag)
    info = []
    for e in errors:
        loc = tuple(e.get("loc", ()))
        _, _, tag = _resolve(loc, data, e["type"])
        if tag is None:
            info.append(None)
            continue
        site, branch = loc[:tag], loc[tag]
        info.append((site, branch))
        if site not in best or len(loc) > best[site][0]:
            best[site] = (len(loc), branch)
    return [e for e, i in zip(errors, info) if i is None or best[i[0]][1] == i[1]]


def _show(value: Any, limit: int = 60) -> str:
    """A value as the YAML it came from, shortened to ``limit`` characters."""

    def fmt(v: Any) -> str:
        if isinstance(v, bool):
            return "true" if v else "false"
        if v is None:
            return "null"
        if isinstance(v, str):
            return repr(v)
        if isinstance(v, dict):
            return "{" + ", ".join(f"{k}: {fmt(x)}" for k, x in v.items()) + "}"
        if isinstance(v, (list, tuple)):
            return "[" + ", ".join(fmt(x) for x in v) + "]"
        return repr(v)

    text = fmt(value)
    return text if len(text) <= limit else text[: limit - 1] + "…"


def locate(err: dict, data: Any, lines: dict[tuple, int], source: str) -> tuple[list, Any, str, str]:
    """Where a pydantic error ``err`` points in the document ``data``: (its real path, the value there or _ABSENT,
    ``FILE:LINE`` (the line of the deepest part of the path the document has), the dotted FIELD)."""
    real, node, _ = _resolve(tuple(err.get("loc", ())), data, err["type"])
    probe = tuple(real)
    while probe not in lines and probe:
        probe = probe[:-1]
    line = lines.get(probe)
    where = f"{source}:{line}" if line else source
    return real, node, where, ".".join(str(p) for p in real) or "(top level)"
