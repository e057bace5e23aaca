"""Number fields take numbers: :data:`Num` and :data:`Int` refuse text and flags (pydantic's lax mode read
``'0.5'`` as 0.5 and ``true`` as 1.0) with a rule the profile's error line names with the field."""

from __future__ import annotations

from typing import Annotated, Any, Optional

from pydantic import BeforeValidator

FLAG = "must be a number, not a flag (YAML reads true/false/yes/no/on/off as one)"
TEXT = "must be a number, not text (write the number without quotes)"


class ExponentNumber(str):
    """A plain YAML scalar such as ``5e-2``, ``4.18e2`` or ``1.0e6``: a number in YAML 1.2, text to PyYAML's YAML 1.1
    rules (an exponent without a dot or without a sign). The loader keeps it as this text, so a text field (a name
    ``1e5``) keeps what was written, and a number field reads it as the number (:func:`refuse_non_number`)."""


def refuse_non_number(value: Any) -> Any:
    """``value`` as it is (a plain YAML exponent number, :class:`ExponentNumber`, as its float), or ValueError when it
    is a flag (:data:`FLAG`) or text (:data:`TEXT` for a number in quotes)."""
    if isinstance(value, ExponentNumber):
        return float(value)
    if isinstance(value, bool):
        raise ValueError(FLAG)
    if isinstance(value, (str, bytes)):
        try:
            float(value)
        except ValueError:
            raise ValueError("must be a number") from None
        raise ValueError(TEXT)  # a number in quotes
    return value


#: the check, for an ``Annotated[float, Field(…), NUMBER]`` whose bounds come first (the JSON Schema keeps them)
NUMBER = BeforeValidator(refuse_non_number)
#: a number field: an int or a float (a flag or text is refused)
Num = Annotated[float, BeforeValidator(refuse_non_number)]
#: a whole-number field: an int (a flag or text is refused)
Int = Annotated[int, BeforeValidator(refuse_non_number)]
#: an optional number field (None: not given); the check sits outside the union, so the JSON Schema keeps its
#: plain bounds (exclusiveMinimum …)
OptNum = Annotated[Optional[float], BeforeValidator(refuse_non_number)]
#: an optional whole-number field
OptInt = Annotated[Optional[int], BeforeValidator(refuse_non_number)]
