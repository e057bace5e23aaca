"""IEC 61131-3 identifiers: what a Structured Text name may be (:func:`st_identifier_problem`).

An identifier is a letter or ``_``, then letters, digits and ``_``, with no two ``_`` in a row and none at the end
(IEC 61131-3, "Identifiers"); identifiers are case-insensitive, so ``nE`` *is* the standard function ``NE``. A name
must not be a keyword, an elementary or generic data type, a standard function or a standard function block of the
standard (:data:`RESERVED`, compared in upper case): a strict compiler (matiec, the compiler of Beremiz/OpenPLC)
refuses the declaration or, worse, calls the function.
"""

from __future__ import annotations

import re

_KEYWORDS = """
ACTION END_ACTION ARRAY OF AT CASE ELSE END_CASE CONFIGURATION END_CONFIGURATION CONSTANT EN ENO EXIT FALSE F_EDGE
FOR TO BY DO END_FOR FUNCTION END_FUNCTION FUNCTION_BLOCK END_FUNCTION_BLOCK IF THEN ELSIF END_IF INITIAL_STEP
END_STEP NON_RETAIN PROGRAM WITH END_PROGRAM R_EDGE READ_ONLY READ_WRITE REPEAT UNTIL END_REPEAT RESOURCE ON
END_RESOURCE RETAIN RETURN STEP STRUCT END_STRUCT TASK TRANSITION FROM END_TRANSITION TRUE TYPE END_TYPE VAR
END_VAR VAR_INPUT VAR_OUTPUT VAR_IN_OUT VAR_TEMP VAR_EXTERNAL VAR_ACCESS VAR_CONFIG VAR_GLOBAL WHILE END_WHILE
CONTINUE CLASS END_CLASS INTERFACE END_INTERFACE METHOD END_METHOD EXTENDS IMPLEMENTS FINAL ABSTRACT PUBLIC PRIVATE
PROTECTED INTERNAL OVERRIDE THIS SUPER NAMESPACE END_NAMESPACE USING REF_TO REF NULL PRIORITY SINGLE INTERVAL
"""
_ELEMENTARY = """
BOOL SINT INT DINT LINT USINT UINT UDINT ULINT REAL LREAL TIME LTIME DATE LDATE TIME_OF_DAY TOD LTIME_OF_DAY LTOD
DATE_AND_TIME DT LDATE_AND_TIME LDT STRING WSTRING CHAR WCHAR BYTE WORD DWORD LWORD
"""
_TYPES = _ELEMENTARY + """
ANY ANY_DERIVED ANY_ELEMENTARY ANY_MAGNITUDE ANY_NUM ANY_REAL ANY_INT ANY_UNSIGNED ANY_SIGNED ANY_DURATION ANY_BIT
ANY_CHARS ANY_STRING ANY_CHAR ANY_DATE
"""
_FUNCTIONS = """
TRUNC ABS SQRT LN LOG EXP SIN COS TAN ASIN ACOS ATAN ATAN2 ADD MUL SUB DIV MOD EXPT MOVE SHL SHR ROR ROL AND OR XOR
NOT SEL MAX MIN LIMIT MUX GT GE EQ LE LT NE LEN LEFT RIGHT MID CONCAT INSERT DELETE REPLACE FIND ADD_TIME SUB_TIME
MUL_TIME DIV_TIME ADD_LTIME SUB_LTIME MUL_LTIME DIV_LTIME ADD_TOD_TIME ADD_DT_TIME SUB_TOD_TIME SUB_DT_TIME
SUB_DATE_DATE SUB_TOD_TOD SUB_DT_DT CONCAT_DATE_TOD CONCAT_DATE CONCAT_TOD CONCAT_DT SPLIT_DATE SPLIT_TOD SPLIT_DT
DAY_OF_WEEK TO_BIG_ENDIAN TO_LITTLE_ENDIAN FROM_BIG_ENDIAN FROM_LITTLE_ENDIAN IS_VALID IS_VALID_BCD
SR RS R_TRIG F_TRIG CTU CTD CTUD CTU_INT CTU_DINT CTU_LINT CTU_UDINT CTU_ULINT CTD_INT CTD_DINT CTD_LINT CTD_UDINT
CTD_ULINT CTUD_INT CTUD_DINT CTUD_LINT CTUD_UDINT CTUD_ULINT TP TON TOF LTP LTON LTOF
"""
#: elementary types whose conversions ``<A>_TO_<B>``, ``TRUNC_<A>`` … are standard functions too
_CONVERTIBLE = tuple(_ELEMENTARY.split()) + ("BCD",)

#: every reserved name, upper case (conversion functions are matched by :data:`_CONVERSION`)
RESERVED: frozenset[str] = frozenset((_KEYWORDS + _TYPES + _FUNCTIONS).split())
_CONVERSION = re.compile(
    r"(?:(?:%(t)s)_TO_(?:%(t)s)|TO_(?:%(t)s)|TRUNC_(?:%(t)s)|(?:%(t)s)_TRUNC_(?:%(t)s))\Z" % {"t": "|".join(_CONVERTIBLE)}
)
_SHAPE = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")


def is_reserved(name: str) -> bool:
    """True when ``name`` (any case) is an IEC 61131-3 keyword, data type, standard function or function block."""
    up = name.upper()
    return up in RESERVED or bool(_CONVERSION.match(up))


def st_identifier_problem(name: str) -> str | None:
    """Why ``name`` cannot be an IEC 61131-3 identifier of its own (None when it can)."""
    if not _SHAPE.match(name):
        return "must be an IEC 61131-3 identifier: a letter or _, then letters, digits and _"
    if "__" in name:
        return "must not contain two _ in a row (IEC 61131-3 identifiers)"
    if name.endswith("_"):
        return "must not end with _ (IEC 61131-3 identifiers)"
    if is_reserved(name):
        return (f"is the IEC 61131-3 keyword, type or standard function {name.upper()} (Structured Text names are "
                "case-insensitive)")
    return None
