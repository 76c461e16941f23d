"""A validator for the subset of XML Schema that tests/data/junit.xsd uses, in the standard library only.

It reads the schema's global ``xs:element`` declarations and checks a document against them: every element is
declared; its children are among the ``ref``s its declaration allows (order is not checked: the schema's
content models are unbounded choices except ``testsuites``' single sequence); attributes are declared, those
with ``use="required"`` present, and values of a type restricted by an ``xs:pattern`` match it in full; text
only where the type is ``xs:string`` or ``mixed``. :func:`problems` returns every violation (empty = valid).
"""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET
from dataclasses import dataclass, field
from pathlib import Path

XS = "{http://www.w3.org/2001/XMLSchema}"
SCHEMA = Path(__file__).resolve().parent / "data" / "junit.xsd"


@dataclass
class Decl:
    children: set[str] = field(default_factory=set)
    attributes: dict[str, str] = field(default_factory=dict)  # name -> type
    required: set[str] = field(default_factory=set)
    text: bool = False


def load(path=SCHEMA) -> tuple[dict[str, Decl], dict[str, re.Pattern]]:
    """The element declarations and the pattern-restricted simple types of an XSD."""
    root = ET.parse(path).getroot()
    patterns = {t.get("name"): re.compile(p.get("value"))
                for t in root.findall(f"{XS}simpleType") for p in t.iter(f"{XS}pattern")}
    decls = {}
    for el in root.findall(f"{XS}element"):
        d = Decl(text=el.get("type") == "xs:string")
        for ct in el.findall(f"{XS}complexType"):
            d.text = ct.get("mixed") == "true"
            d.children = {c.get("ref") for c in ct.iter(f"{XS}element") if c.get("ref")}
            for a in ct.iter(f"{XS}attribute"):
                d.attributes[a.get("name")] = a.get("type", "xs:string")
                if a.get("use") == "required":
                    d.required.add(a.get("name"))
        decls[el.get("name")] = d
    return decls, patterns


def problems(document: str, path=SCHEMA) -> list[str]:
    """Every way ``document`` (XML text) breaks the schema at ``path``; empty when it is valid."""
    decls, patterns = load(path)
    out = []

    def walk(node: ET.Element, where: str) -> None:
        here = f"{where}/{node.tag}"
        d = decls.get(node.tag)
        if d is None:
            out.append(f"{here}: element not declared")
            return
        for name in sorted(d.required - node.attrib.keys()):
            out.append(f"{here}: required attribute {name} missing")
        for name, value in node.attrib.items():
            if name not in d.attributes:
                out.append(f"{here}: attribute {name} not declared")
            elif d.attributes[name] in patterns and not patterns[d.attributes[name]].fullmatch(value):
                out.append(f"{here}: {name}={value!r} does not match {d.attributes[name]}")
        if not d.text and (node.text or "").strip():
            out.append(f"{here}: text not allowed")
        for child in node:
            if child.tag not in d.children:
                out.append(f"{here}: child {child.tag} not allowed")
            if not d.text and (child.tail or "").strip():
                out.append(f"{here}: text not allowed")
            walk(child, here)

    walk(ET.fromstring(document), "")
    return out
