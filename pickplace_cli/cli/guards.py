"""Checks every command makes on its files before any work: no output is a file the command reads."""

from __future__ import annotations

from typing import Iterable, Optional


def refuse_overwriting_inputs(outputs: Iterable[tuple[str, Optional[str]]],
                              inputs: Iterable[tuple[str, Optional[str]]], profile: Optional[str] = "") -> None:
    """ExportError (exit 1, one line) when an output (option, path) is a file the command reads: an input (option,
    path) or the profile ``profile`` resolves to (a file, or a shipped name; "" when the command reads none). A
    profile that cannot be resolved is left to the profile's own error."""
    from ..model.errors import PickplaceError
    from ..model.files import refuse_inputs_as_outputs

    inputs = list(inputs)
    if profile != "":
        from ..model.profile import resolve_profile_path

        try:
            inputs.append(("-p", str(resolve_profile_path(profile))))
        except PickplaceError:
            pass
    refuse_inputs_as_outputs(outputs, inputs)
