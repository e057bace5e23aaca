"""MkDocs hook: the manual's two reference pages, generated at every build from the code itself.

* ``reference/cli.md`` from the Typer app (``pickplace_cli.cli.app``): every command and sub-command with its usage,
  description, arguments and options, exactly as ``--help`` prints them;
* ``reference/profile.md`` from the pydantic models (:func:`pickplace_cli.profile_schema`): every section and field
  of a profile with its type, default and description (units included).

Nothing is copied by hand, so neither page can go stale. ``python docs/hooks/reference.py DIR`` writes both pages
into DIR, to read them without building the site.
"""

from __future__ import annotations

import html
import sys
from pathlib import Path
from typing import Any

CLI_PAGE = "reference/cli.md"
PROFILE_PAGE = "reference/profile.md"


# ------------------------------------------------------------------------------------------------------ the CLI


def _anchor(path: str) -> str:
    """The heading id of a command's section (``pickplace profile init`` → ``pickplace-profile-init``)."""
    return path.replace(" ", "-")


def _command_sections(cmd, ctx, level: int) -> list[str]:
    path = ctx.command_path
    out = [f"{'#' * level} `{path}` {{ #{_anchor(path)} }}", ""]
    usage = cmd.get_usage(ctx).removeprefix("Usage: ")
    out += ["```text", usage, "```", ""]
    for para in (cmd.help or "").split("\n\n"):
        text = " ".join(para.replace("\b", "").split())
        if text:
            out += [f"<p>{html.escape(text)}</p>", ""]
    records = [(type(p).__name__, r) for p in cmd.get_params(ctx) if (r := p.get_help_record(ctx))]
    for title, kind in (("Arguments", "Argument"), ("Options", "Option")):
        rows = [r for k, r in records if k.endswith(kind)]
        if rows:
            out += [f"**{title}**", "", "<dl>"]
            for names, text in rows:
                out += [f"<dt><code>{html.escape(names)}</code></dt>", f"<dd>{html.escape(' '.join(text.split()))}</dd>"]
            out += ["</dl>", ""]
    if hasattr(cmd, "list_commands"):  # a group (typer carries its own copy of click: no isinstance)
        subs = cmd.list_commands(ctx)
        out += ["**Commands**", ""]
        out += [f"- [`{path} {name}`](#{_anchor(f'{path} {name}')}): "
                f"{html.escape(cmd.get_command(ctx, name).get_short_help_str(limit=120))}" for name in subs]
        out.append("")
        for name in subs:
            sub = cmd.get_command(ctx, name)
            out += _command_sections(sub, type(ctx)(sub, info_name=name, parent=ctx), level + 1)
    return out


def cli_reference() -> str:
    """The CLI reference page (Markdown) from the Typer app."""
    import typer

    from pickplace_cli.cli import app

    root = typer.main.get_command(app)
    ctx = root.context_class(root, info_name="pickplace")
    lines = ["# Command reference", "",
             "Every command and option as `pickplace COMMAND --help` prints it, generated from the program itself "
             "at each build of this manual. The pages under *Commands* explain what they do and show them at work.",
             ""]
    return "\n".join(lines + _command_sections(root, ctx, 2)) + "\n"


# ------------------------------------------------------------------------------------------------ the profile


def _type_of(spec: dict[str, Any]) -> str:
    """A field's type in words: number, text, a [list], a section (linked), one of several."""
    if "$ref" in spec:
        name = spec["$ref"].rsplit("/", 1)[-1]
        return f"[{name}](#{name.lower()})"
    if "const" in spec:
        return f"`{spec['const']}`"
    if "enum" in spec:
        return " \\| ".join(f"`{v}`" for v in spec["enum"])
    for key in ("anyOf", "oneOf"):
        if key in spec:
            kinds = [_type_of(s) for s in spec[key] if s.get("type") != "null"]
            optional = any(s.get("type") == "null" for s in spec[key])
            return " or ".join(kinds) + (" (optional)" if optional else "")
    kind = spec.get("type")
    if kind == "array":
        if "prefixItems" in spec:
            return "[" + ", ".join(_type_of(s) for s in spec["prefixItems"]) + "]"
        return f"list of {_type_of(spec.get('items', {}))}"
    return {"number": "number", "integer": "integer", "string": "text", "boolean": "true/false",
            "object": "mapping"}.get(kind, kind or "any")


def _bounds(spec: dict[str, Any]) -> str:
    words = {"exclusiveMinimum": ">", "minimum": "≥", "exclusiveMaximum": "<", "maximum": "≤", "minLength": "length ≥"}
    parts = [f"{w} {spec[k]:g}" if isinstance(spec[k], (int, float)) else f"{w} {spec[k]}"
             for k, w in words.items() if k in spec]
    return ", ".join(parts)


def _cell(text: str) -> str:
    return html.escape(" ".join(str(text).split()), quote=False).replace("|", "\\|")


def _model_table(name: str, model: dict[str, Any]) -> list[str]:
    out = [f"## {name} {{ #{name.lower()} }}", ""]
    if model.get("description"):
        out += [_cell(model["description"]), ""]
    required = set(model.get("required", ()))
    out += ["| field | type | required / default | description |", "|---|---|---|---|"]
    for field, spec in model.get("properties", {}).items():
        kind = _type_of(spec)
        bounds = _bounds(spec)
        if bounds:
            kind += f" ({bounds})"
        need = "required" if field in required else (f"`{spec['default']!r}`".replace("None", "null")
                                                     if "default" in spec else "optional")
        out.append(f"| `{field}` | {kind} | {need} | {_cell(spec.get('description', ''))} |")
    return out + [""]


def profile_reference() -> str:
    """The profile reference page (Markdown) from the pydantic models' JSON Schema."""
    from pickplace_cli import profile_schema

    schema = profile_schema()
    defs = schema.get("$defs", {})
    lines = ["# Profile reference", "",
             "Every section and field of a profile file, generated from the validating models at each build of this "
             "manual (the same models write the JSON Schema an editor uses: see [Profiles](../profiles.md#editing-a-"
             "profile-in-an-editor)). Units are SI: m, s, rad, kg, N·m. A section's table lists its fields; a type "
             "in brackets links to its section. `robot` is one of `DeltaModel`, `ScaraModel` or `GantryModel`, "
             "chosen by its `kind`.", ""]
    lines += _model_table("Profile", schema)
    for name in sorted(defs):
        lines += _model_table(name, defs[name])
    return "\n".join(lines) + "\n"


# ------------------------------------------------------------------------------------------------ MkDocs hooks


def on_files(files, config):  # noqa: D103 - MkDocs hook
    from mkdocs.structure.files import File

    for uri, content in ((CLI_PAGE, cli_reference()), (PROFILE_PAGE, profile_reference())):
        files.append(File.generated(config, uri, content=content))
    return files


if __name__ == "__main__":
    target = Path(sys.argv[1] if len(sys.argv) > 1 else ".")
    (target / "reference").mkdir(parents=True, exist_ok=True)
    (target / CLI_PAGE).write_text(cli_reference(), encoding="utf-8")
    (target / PROFILE_PAGE).write_text(profile_reference(), encoding="utf-8")
