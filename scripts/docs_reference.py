"""The Python API reference as plain Markdown, rendered from the code's docstrings (Google style, read by griffe).

A reference page (docs/reference/*.md) is prose the page's author writes, with one entry per object:

    <!-- reference: fleetsim.planning.plans.FleetPlan -->
    ... generated ...
    <!-- end reference -->

Everything between the two comments is generated, so the page reads whole on GitHub and in an editor and
MkDocs builds the site from the same file. An entry shows the object's signature, where it is defined,
its docstring's sections and its documented public members; each object and member gets an anchor named
by its path (``#fleetsim.planning.plans.FleetPlan``, ``#fleetsim.planning.plans.FleetPlan.fixed_legs``),
which other pages link to. A docstring's cross-reference ``[`FleetLeg`][fleetsim.planning.plans.FleetLeg]``
becomes a link to the entry that shows it. Options after the path: ``no-signature`` shows a class without
its constructor (one built by a function, whose private fields would only confuse); words in
parentheses are a note to the page's author. Rendering depends on the docstrings only (no clock, no
order of a set), so the pages change exactly when the docstrings do.
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path

import griffe

ENTRY = re.compile(
    r"^<!-- reference: (?P<path>[\w.]+)(?P<options>[^\n]*?) -->\n(?P<body>.*?)^<!-- end reference -->$",
    re.M | re.S,
)
OPTIONS = frozenset({"no-signature"})
_CROSS_REFERENCE = re.compile(r"\[(?P<text>[^\]\n]+)\]\[(?P<target>[\w.]*)\]")
_HEADING = re.compile(r"^(#{1,6}) ")
_CODE_SPAN = re.compile(r"(`+)[^`]*?\1")
# "The thesis" is named once, with its full reference, on the documentation's home page; each mention links there.
THESIS = "../index.md#background"
_THESIS = re.compile(r"(?i)(?<![\[\w])((?:the )?thesis(?:['’]s)?)(?![\w\]])")
_SIGNATURE_WIDTH = 100  # longer signatures get one parameter per line


@dataclass(frozen=True)
class Entry:
    """One ``<!-- reference: PATH -->`` entry of a page: what it shows and at which heading level."""

    page: Path
    path: str
    options: frozenset[str]
    level: int


@dataclass
class Rendering:
    """The reference pages' entries and anchors, and the cross-references no entry resolves."""

    package: griffe.Module
    anchors: dict[str, tuple[Path, str]] = field(default_factory=dict)  # a path -> (its page, its anchor)
    unresolved: list[str] = field(default_factory=list)  # "object path: target" of broken references


def load_package(root: Path) -> griffe.Module:
    """The fleetsim package as griffe reads it from the source in ``root`` (nothing is imported)."""
    package = griffe.load("fleetsim", search_paths=[str(root)], docstring_parser="google")
    assert isinstance(package, griffe.Module)
    return package


def find(package: griffe.Module, path: str) -> griffe.Object:
    """The object at ``path`` (``fleetsim.x.Y``), an alias followed to what it names."""
    found = package[path.removeprefix("fleetsim.")]
    return found.final_target if isinstance(found, griffe.Alias) else found


def entries(page: Path, text: str) -> list[Entry]:
    """The entries of a page's text, each with the heading level its heading takes (one below the section's)."""
    stripped = ENTRY.sub(lambda m: f"<!-- reference: {m['path']}{m['options']} -->\n<!-- end reference -->", text)
    found: list[Entry] = []
    level, fenced = 1, False
    for line in stripped.splitlines():
        if line.lstrip().startswith("```"):
            fenced = not fenced
        elif not fenced and (heading := _HEADING.match(line)):
            level = len(heading.group(1))
        elif match := ENTRY.match(line + "\n<!-- end reference -->"):
            options = frozenset(match["options"].split("(")[0].split())
            unknown = options - OPTIONS
            if unknown:
                msg = f"{page}: reference entry {match['path']}: unknown option(s) {sorted(unknown)}"
                raise ValueError(msg)
            found.append(Entry(page, match["path"], options, min(level + 1, 5)))
    return found


def render_pages(pages: Mapping[Path, str], package: griffe.Module) -> tuple[dict[Path, str], list[str]]:
    """Every page's text with its entries rendered anew; and the cross-references that resolved nowhere."""
    rendering = Rendering(package)
    found = {page: entries(page, text) for page, text in pages.items()}
    for page_entries in found.values():
        for entry in page_entries:
            _index(rendering, entry)
    rendered: dict[Path, str] = {}
    for page, text in pages.items():
        bodies = iter(found[page])

        def replace(match: re.Match[str], bodies: Iterator[Entry] = bodies) -> str:
            entry = next(bodies)
            body = render_entry(rendering, entry)
            return f"<!-- reference: {match['path']}{match['options']} -->\n{body}<!-- end reference -->"

        rendered[page] = ENTRY.sub(replace, text)
    return rendered, rendering.unresolved


def _index(rendering: Rendering, entry: Entry) -> None:
    obj = find(rendering.package, entry.path)
    for name in _names(entry.path, obj):
        rendering.anchors.setdefault(name, (entry.page, entry.path))
    for member_name, member in documented_members(obj):
        anchor = f"{entry.path}.{member_name}"
        for name in _names(anchor, member):
            rendering.anchors.setdefault(name, (entry.page, anchor))


def _names(path: str, obj: griffe.Object) -> list[str]:
    """The paths an object is known by: as the page names it and where it is defined."""
    return [path] if obj.path == path else [path, obj.path]


def documented_members(obj: griffe.Object) -> list[tuple[str, griffe.Object]]:
    """A class's own public members that have a docstring of their own, in source order."""
    if not obj.is_class:
        return []
    return [
        (name, member)
        for name, member in obj.members.items()
        if not name.startswith("_") and not isinstance(member, griffe.Alias) and member.docstring is not None
    ]


def render_entry(rendering: Rendering, entry: Entry) -> str:
    obj = find(rendering.package, entry.path)
    lines = [*_anchor_tags(_names(entry.path, obj)), "", f"{'#' * entry.level} `{obj.name}`", ""]
    lines += _code(_signature(obj, show_init="no-signature" not in entry.options))
    lines += ["", _what(obj), ""]
    lines += _docstring(rendering, entry.page, obj)
    if _is_enum(obj):
        lines += _enum_members(obj)
    for name, member in documented_members(obj):
        anchor = f"{entry.path}.{name}"
        lines += [*_anchor_tags(_names(anchor, member)), "", f"{'#' * min(entry.level + 1, 6)} `{name}`", ""]
        lines += _code(_signature(member, show_init=True))
        lines += ["", _what(member), ""]
        lines += _docstring(rendering, entry.page, member)
    return "\n".join(_tidy(lines)) + "\n"


def _anchor_tags(names: Iterable[str]) -> list[str]:
    return ["".join(f'<a id="{name}"></a>' for name in names)]


def _code(signature: str) -> list[str]:
    # ```pyi, not ```python: the examples runner (tests/docs/examples.py) executes ```python blocks.
    return ["```pyi", signature, "```"]


def _tidy(lines: list[str]) -> list[str]:
    """No two blank lines in a row, none at either end."""
    out: list[str] = []
    for line in lines:
        if line or (out and out[-1]):
            out.append(line.rstrip())
    while out and not out[-1]:
        out.pop()
    return out


# -- signatures ------------------------------------------------------------------------------------


def _signature(obj: griffe.Object, *, show_init: bool) -> str:
    if isinstance(obj, griffe.Function):
        parameters = list(obj.parameters)
        if obj.parent is not None and obj.parent.is_class and "staticmethod" not in obj.labels and parameters:
            parameters = parameters[1:]  # self or cls
        returns = f" -> {obj.returns}" if obj.returns is not None else ""
        return _call(obj.name, parameters, returns)
    if isinstance(obj, griffe.Class):
        parameters = [p for p in obj.parameters if p.name != "self"] if show_init else []
        if show_init and parameters:
            return _call(obj.name, parameters, "")
        bases = ", ".join(str(base) for base in obj.bases)
        return f"class {obj.name}({bases})" if bases else f"class {obj.name}"
    if not isinstance(obj, griffe.Attribute):
        return obj.name
    annotation = f": {obj.annotation}" if obj.annotation is not None else ""
    value = f" = {obj.value}" if obj.value is not None and "property" not in obj.labels else ""
    return f"{obj.name}{annotation}{value}"


def _call(name: str, parameters: list[griffe.Parameter], returns: str) -> str:
    shown = _parameters(parameters)
    one_line = f"{name}({', '.join(shown)}){returns}"
    if len(one_line) <= _SIGNATURE_WIDTH or not shown:
        return one_line
    return f"{name}(\n" + "".join(f"    {item},\n" for item in shown) + f"){returns}"


def _parameters(parameters: list[griffe.Parameter]) -> list[str]:
    kinds = griffe.ParameterKind
    shown: list[str] = []
    star_shown = False
    for index, parameter in enumerate(parameters):
        kind = parameter.kind
        if kind is kinds.keyword_only and not star_shown:
            shown.append("*")
            star_shown = True
        prefix = {kinds.var_positional: "*", kinds.var_keyword: "**"}.get(kind, "")  # type: ignore[arg-type]
        star_shown = star_shown or kind is kinds.var_positional
        text = prefix + parameter.name
        if parameter.annotation is not None:
            text += f": {parameter.annotation}"
        if parameter.default is not None:
            text += f" = {parameter.default}" if parameter.annotation is not None else f"={parameter.default}"
        shown.append(text)
        last_positional_only = kind is kinds.positional_only and (
            index + 1 == len(parameters) or parameters[index + 1].kind is not kinds.positional_only
        )
        if last_positional_only:
            shown.append("/")
    return shown


def _is_enum(obj: griffe.Object) -> bool:
    return isinstance(obj, griffe.Class) and any(
        str(base).split(".")[-1].endswith(("Enum", "Flag")) for base in obj.bases
    )


def _what(obj: griffe.Object) -> str:
    """A line saying what the object is and where it is defined."""
    if obj.is_function:
        kind = "Method" if obj.parent is not None and obj.parent.is_class else "Function"
        labels = sorted(obj.labels & {"classmethod", "staticmethod"})
        return f"{kind} `{obj.path}`" + (f" ({', '.join(labels)})." if labels else ".")
    if isinstance(obj, griffe.Class):
        if _is_enum(obj):
            kind = "Enumeration"
        elif "dataclass" in obj.labels:
            kind = "Dataclass"
        else:
            kind = "Class"
        bases = [str(base) for base in obj.bases if not str(base).split(".")[-1].endswith(("Enum", "Flag"))]
        if _is_enum(obj) or not bases:
            return f"{kind} `{obj.path}`."
        return f"{kind} `{obj.path}`; bases " + ", ".join(f"`{base}`" for base in bases) + "."
    kind = "Property" if "property" in obj.labels else "Attribute"
    return f"{kind} `{obj.path}`."


def _enum_members(obj: griffe.Object) -> list[str]:
    """The enumeration's members and values, unless its docstring's ``Attributes:`` section lists them all."""
    documented = {
        entry.name
        for section in (obj.docstring.parse("google") if obj.docstring is not None else [])
        if section.kind is griffe.DocstringSectionKind.attributes
        for entry in section.value
    }
    members = [
        (name, member)
        for name, member in obj.members.items()
        if isinstance(member, griffe.Attribute) and not name.startswith("_")
        if "property" not in member.labels and member.value is not None
    ]
    if {name for name, _ in members} <= documented:
        return []
    if not members:
        return []
    return ["**Members**", "", *(f"- `{name}` = `{member.value}`" for name, member in members), ""]


# -- docstrings ------------------------------------------------------------------------------------


def _docstring(rendering: Rendering, page: Path, obj: griffe.Object) -> list[str]:
    if obj.docstring is None:
        return []
    lines: list[str] = []
    for section in obj.docstring.parse("google"):
        lines += _section(rendering, page, obj, section)
        lines.append("")
    return lines


def _section(rendering: Rendering, page: Path, obj: griffe.Object, section: griffe.DocstringSection) -> list[str]:
    kinds = griffe.DocstringSectionKind

    def text(value: str) -> str:
        return _links(rendering, page, obj, value)

    if section.kind is kinds.text:
        return text(section.value).splitlines()
    if section.kind is kinds.examples:
        lines: list[str] = []
        for kind, value in section.value:
            block = ["```pycon", *value.splitlines(), "```"] if kind is griffe.DocstringSectionKind.examples else []
            lines += [*(block or text(value).splitlines()), ""]
        return ["**Examples**", "", *lines]
    if section.kind in {kinds.admonition, kinds.deprecated}:
        title = section.title or section.kind.value.capitalize()
        body = text(getattr(section.value, "description", str(section.value)))
        return [f"> **{title}**", ">", *(f"> {line}".rstrip() for line in body.splitlines())]
    titles = {
        kinds.parameters: "Parameters",
        kinds.other_parameters: "Other parameters",
        kinds.attributes: "Attributes",
        kinds.returns: "Returns",
        kinds.yields: "Yields",
        kinds.receives: "Receives",
        kinds.raises: "Raises",
        kinds.warns: "Warns",
        kinds.functions: "Functions",
        kinds.classes: "Classes",
        kinds.modules: "Modules",
    }
    title = section.title or titles.get(section.kind, section.kind.value.capitalize())
    return [f"**{title}**", "", *(line for item in section.value for line in _item(item, text))]


def _item(item: griffe.DocstringElement, text: object) -> list[str]:
    """One list item of a section: name, type (and default), then the description."""
    assert callable(text)
    name = getattr(item, "name", "") or ""
    annotation = item.annotation
    default = getattr(item, "default", None)
    if name and not isinstance(item, (griffe.DocstringRaise, griffe.DocstringWarn)):
        details = [f"`{annotation}`"] if annotation is not None else []
        if default is not None:
            details.append(f"default `{default}`")
        head = f"`{name}`" + (f" ({', '.join(details)})" if details else "")
    else:
        head = f"`{annotation}`" if annotation is not None else f"`{name}`"
    description = text(item.description).strip().splitlines()
    if not description:
        return [f"- {head}"]
    return [f"- {head}: {description[0]}", *(f"    {line}".rstrip() for line in description[1:])]


def _links(rendering: Rendering, page: Path, obj: griffe.Object, text: str) -> str:
    """Cross-references (``[`X`][path]``, ``[path][]``) as links to the entries that show their targets."""

    def link(match: re.Match[str]) -> str:
        target = match["target"] or match["text"].strip("`")
        where = rendering.anchors.get(target) or rendering.anchors.get(_canonical(rendering.package, target))
        if where is None:
            rendering.unresolved.append(f"{obj.path}: {target}")
            return match["text"]
        target_page, anchor = where
        href = f"#{anchor}" if target_page == page else f"{target_page.name}#{anchor}"
        return f"[{match['text']}]({href})"

    return _thesis_links(_CROSS_REFERENCE.sub(link, text))


def _thesis_links(text: str) -> str:
    """Each mention of the thesis outside code a link to its reference."""
    parts, last = [], 0
    for code in _CODE_SPAN.finditer(text):
        parts += [_THESIS.sub(rf"[\1]({THESIS})", text[last : code.start()]), code[0]]
        last = code.end()
    parts.append(_THESIS.sub(rf"[\1]({THESIS})", text[last:]))
    return "".join(parts)


def _canonical(package: griffe.Module, path: str) -> str:
    try:
        return find(package, path).path
    except (KeyError, griffe.AliasResolutionError, griffe.CyclicAliasError):
        return path
