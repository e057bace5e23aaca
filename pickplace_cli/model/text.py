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
    if bom:
        head = head[2:]
    halves = False
    if len(head) >= 4:  # ASCII text in UTF-16: one byte of each pair NUL, the other printable (not all zeros)
        for zeros, text in ((head[1::2], head[0::2]), (head[0::2], head[1::2])):
            if not zeros.strip(b"\0") and text and all(b in (9, 10, 13) or 32 <= b < 127 for b in text):
                halves = True
    if not halves:
        return ""
    return " (UTF-16 text, e.g. Excel's \"Unicode Text\"? save it as \"CSV UTF-8\")" if csv else " (UTF-16 text? save it as UTF-8)"


def decode_text(raw: bytes, source: str, kind: str, error: type, csv: bool = True) -> str:
    """The UTF-8 text of a file's bytes ``raw``, or ``error`` in one line: NUL bytes ("a binary file …, not
    ``kind``", with a hint when it looks like UTF-16) or bytes that are not UTF-8."""
    if b"\0" in raw:
        raise error(f"{source}: a binary file (NUL bytes), not {kind}{utf16_hint(raw, csv=csv)}")
    try:
        return raw.decode("utf-8")
    except UnicodeDecodeError:
        raise error(f"{source}: not a text (UTF-8) file") from None


def quoted(text: str, most: int = 60) -> str:
    """``text`` quoted, cut to ``most`` characters with its length (a value pasted by mistake, a 5,000-digit number,
    stays one short line of an error message)."""
    return repr(text) if len(text) <= most else repr(text[:most]) + f" … ({len(text):,} characters)"


def shorten_quoted(message: str, longer_than: int = 200, most: int = 60) -> str:
    """``message`` with every quoted value longer than ``longer_than`` characters cut to ``most`` as :func:`quoted`
    cuts it (an error line that names a 5,000-digit number stays one short line; a file's path is left whole)."""
    import re

    return re.sub(r"'([^'\n]{%d,})'" % (longer_than + 1), lambda m: quoted(m.group(1), most), message)
