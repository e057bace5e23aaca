"""Number fields take numbers: :data:`Num` and :data:`Int` refuse text and flags (pydantic's lax mode read
``'0.5'`` as 0.5 and ``true`` as 1.0) with a rule the profile's error line names with the field."""

from __future__ import annotations

from typing import Annotated, Any, Optional

from pydantic import BeforeValidator

FLAG = "must be a number, not a flag (YAML reads true/false/yes/no/on/off as one)"
TEXT = "must be a number, not text (write the number without quotes)"


def refuse_non_number(value: Any) -> Any:
    """``value`` as it is, or ValueError when it is a flag (:data:`FLAG`) or text (:data:`TEXT` for a number in
    quotes)."""
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
