"""Reading numbers and text from users' files: what Python's ``float`` and decoders accept but a user did not mean."""

from __future__ import annotations


def plain_float(text: str) -> float:
    """``float(text)`` for a number written the plain way: ASCII digits, sign, point, exponent (and nan/inf, which
    the callers refuse by name). ValueError for what ``float`` also takes but a typo or a locale makes: digit
    group underscores (``0.15_25``), other scripts' digits, full-width characters."""
    if "_" in text or not text.isascii():
        raise ValueError(text)
    return float(text)


def utf16_hint(head: bytes | str, csv: bool = True) -> str:
    """" (UTF-16 …? save it as UTF-8)" when the start of a file that has NUL bytes looks like UTF-16 text (a byte-order
    mark, or every other byte NUL), else "" (a str: a line read with surrogateescape, turned back into its bytes)."""
    if isinstance(head, str):
        head = head.encode("utf-8", "surrogateescape")
    head = head[:64]
    bom = head.startswith((b"\xff\xfe", b"\xfe\xff"))
    halves = len(head) >= 4 and (head[1::2].count(0) * 2 >= len(head) - 1 or head[0::2].count(0) * 2 >= len(head) - 1)
    if not (bom or halves):
        return ""
    return " (UTF-16 text, e.g. Excel's \"Unicode Text\"? save it as \"CSV UTF-8\")" if csv else " (UTF-16 text? save it as UTF-8)"
