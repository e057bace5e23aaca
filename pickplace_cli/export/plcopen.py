"""The Structured Text exports as a PLCopen XML project (IEC 61131-10 / PLCopen TC6 XML v2.01, namespace
``http://www.plcopen.org/xml/tc6_0201``), which CODESYS, TwinCAT 3 and Beremiz import (``plan --plcopen-xml``).

The project holds what the ST holds, in the schema's own structure: each ``FUNCTION_BLOCK``, ``PROGRAM`` or
``FUNCTION`` is a ``pou`` (``pouType`` functionBlock, program, function) whose ``interface`` lists its variable blocks
(``VAR_OUTPUT`` → ``outputVars``, ``VAR`` → ``localVars``, ``VAR CONSTANT`` → ``localVars constant="true"``) with
each variable's type (elementary, ``array`` with its dimensions, or ``derived`` for a controller's type such as
``MC_CAM_REF``) and initial value (``simpleValue``, or ``arrayValue`` of ``simpleValue``s: the same shortest decimals
that read back as the same doubles), and whose ``body`` is the ST code inside ``<ST><xhtml:p>``; a ``VAR_GLOBAL
CONSTANT`` list (``--st-dialect codesys``) becomes the ``globalVars constant="true"`` of a configuration. The leading
comment of the ST (provenance, units) is the project's and each POU's ``documentation``.

Deterministic: no clock is read. The schema requires a ``creationDateTime``; it is fixed at
:data:`CREATION_TIME` (and ``productVersion`` is the version of this XML layout, not of the tool), so the same move
gives the same bytes.
"""

from __future__ import annotations

import re
from xml.sax.saxutils import escape, quoteattr

from ..model.errors import ExportError

NS = "http://www.plcopen.org/xml/tc6_0201"
XHTML = "http://www.w3.org/1999/xhtml"
#: the fixed creationDateTime of every export (the schema requires one; no clock is read)
CREATION_TIME = "2000-01-01T00:00:00"
LAYOUT_VERSION = "1"
_ELEMENTARY = {"BOOL", "BYTE", "WORD", "DWORD", "LWORD", "SINT", "INT", "DINT", "LINT", "USINT", "UINT", "UDINT",
               "ULINT", "REAL", "LREAL", "TIME", "DATE", "DT", "TOD"}
_POU = re.compile(r"^(FUNCTION_BLOCK|PROGRAM|FUNCTION) (\w+)(?: : (\w+))?\n(.*?)^END_\1\n", re.M | re.S)
_GLOBAL = re.compile(r"^VAR_GLOBAL CONSTANT\n(.*?)^END_VAR\n", re.M | re.S)
_BLOCK = re.compile(r"^(VAR_OUTPUT|VAR_INPUT|VAR_IN_OUT|VAR CONSTANT|VAR)\n(.*?)^END_VAR\n", re.M | re.S)
_COMMENT = re.compile(r"\(\*(.*?)\*\)", re.S)
_DECL = re.compile(r"(\w+)\s*:\s*(ARRAY\s*\[([^\]]*)\]\s*OF\s*(\w+)|\w+)\s*(?::=\s*(\[[^\]]*\]|[^;]+?))?\s*;"
                   r"\s*(?:\x00(\d+)\x00)?", re.S)
_KIND = {"FUNCTION_BLOCK": "functionBlock", "PROGRAM": "program", "FUNCTION": "function"}
_VARS = {"VAR_OUTPUT": ("outputVars", False), "VAR_INPUT": ("inputVars", False), "VAR_IN_OUT": ("inOutVars", False),
         "VAR": ("localVars", False), "VAR CONSTANT": ("localVars", True)}


def _type(decl_type: str, dims: str | None, base: str | None) -> str:
    def one(name: str) -> str:
        return f"<{name}/>" if name.upper() in _ELEMENTARY else f"<derived name={quoteattr(name)}/>"

    if dims is None:
        return one(decl_type)
    out = ["<array>"]
    for dim in dims.split(","):
        lo, hi = (x.strip() for x in dim.split(".."))
        out.append(f"<dimension lower={quoteattr(lo)} upper={quoteattr(hi)}/>")
    out.append(f"<baseType>{one(base)}</baseType></array>")
    return "".join(out)


def _value(init: str) -> str:
    init = init.strip()
    if init.startswith("["):
        items = [x.strip() for x in init[1:-1].split(",")]
        return ("<arrayValue>" + "".join(f"<value><simpleValue value={quoteattr(x)}/></value>" for x in items)
                + "</arrayValue>")
    return f"<simpleValue value={quoteattr(init)}/>"


def _doc(text: str) -> str:
    return f"<documentation><xhtml:p>{escape(text.strip())}</xhtml:p></documentation>"


def _variables(text: str, comments: list[str]) -> str:
    """The ``variable`` elements of one declaration block (comments replaced by \\x00k\\x00 placeholders)."""
    out = []
    consumed = 0
    for m in _DECL.finditer(text):
        if text[consumed:m.start()].strip(" \n\x000123456789"):
            raise ExportError(f"plcopen: a declaration the writer does not read: {text[consumed:m.start()].strip()!r}")
        consumed = m.end()
        name, decl_type, dims, base, init, note = m.groups()
        inner = None if init is None else re.search(r"\x00(\d+)\x00", init)
        if inner is not None:  # the comment at the head of an array's values
            note = inner.group(1) if note is None else note
            init = init[:inner.start()] + init[inner.end():]
        part = [f"<variable name={quoteattr(name)}><type>{_type(decl_type, dims, base)}</type>"]
        if init is not None:
            part.append(f"<initialValue>{_value(init)}</initialValue>")
        if note is not None:
            part.append(_doc(comments[int(note)]))
        part.append("</variable>")
        out.append("".join(part))
    return "".join(out)


def _protect(text: str) -> tuple[str, list[str]]:
    comments: list[str] = []

    def keep(m):
        comments.append(m.group(1))
        return f"\x00{len(comments) - 1}\x00"

    return _COMMENT.sub(keep, text), comments


def _pou(kind: str, name: str, returns: str | None, inner: str, doc: str) -> str:
    blocks = list(_BLOCK.finditer(inner))
    body = inner[blocks[-1].end():] if blocks else inner
    iface = [f"<returnType>{_type(returns, None, None)}</returnType>"] if returns else []
    for b in blocks:
        tag, const = _VARS[b.group(1)]
        text, comments = _protect(b.group(2))
        attr = ' constant="true"' if const else ""
        iface.append(f"<{tag}{attr}>{_variables(text, comments)}</{tag}>")
    return (f"<pou name={quoteattr(name)} pouType=\"{_KIND[kind]}\"><interface>{''.join(iface)}</interface>"
            f"<body><ST><xhtml:p><![CDATA[{body}]]></xhtml:p></ST></body>{_doc(doc) if doc else ''}</pou>")


def st_to_plcopen(st: str, project: str = "pickplace") -> str:
    """The PLCopen XML (TC6 v2.01) project of the Structured Text ``st`` that pickplace writes (module docstring)."""
    head = _COMMENT.match(st)
    doc = head.group(1) if head else ""
    rest = st[head.end():] if head else st
    pous = [_pou(m.group(1), m.group(2), m.group(3), m.group(4), doc) for m in _POU.finditer(rest)]
    glob = _GLOBAL.search(rest)
    if not pous and glob is None:
        raise ExportError("plcopen: no FUNCTION_BLOCK, PROGRAM, FUNCTION or VAR_GLOBAL CONSTANT list in the text")
    config = "<configurations/>"
    if glob is not None:
        text, comments = _protect(glob.group(1))
        config = (f"<configurations><configuration name=\"{project}_config\"><globalVars name=\"{project}_constants\" "
                  f"constant=\"true\">{_variables(text, comments)}</globalVars></configuration></configurations>")
    return ('<?xml version="1.0" encoding="utf-8"?>\n'
            f'<project xmlns="{NS}" xmlns:xhtml="{XHTML}">\n'
            f'<fileHeader companyName="pickplace" productName="pickplace" productVersion="{LAYOUT_VERSION}" '
            f'creationDateTime="{CREATION_TIME}" contentDescription="pickplace controller tables"/>\n'
            f'<contentHeader name={quoteattr(project)} modificationDateTime="{CREATION_TIME}">'
            '<coordinateInfo><fbd><scaling x="1" y="1"/></fbd><ld><scaling x="1" y="1"/></ld>'
            '<sfc><scaling x="1" y="1"/></sfc></coordinateInfo></contentHeader>\n'
            "<types><dataTypes/><pous>\n" + "\n".join(pous) + "\n</pous></types>\n"
            f"<instances>{config}</instances>\n" + (_doc(doc) if doc else "") + "\n</project>\n")
