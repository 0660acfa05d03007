"""griffe extension: turn the reST markup of the project's docstrings into the Markdown mkdocstrings renders.

The docstrings follow SB3's Sphinx style. mkdocstrings reads their ``:param x:`` fields itself (``docstring_style:
sphinx``); the rest of the text is rendered as Markdown, where three reST constructs would show up raw:

* cross-reference roles, ``:class:`DribbleEnv``` or ``:meth:`~sb3_aac.runtime.RuntimePolicy.act```: the target is
  resolved in the docstring's scope and becomes an optional autoref, a link where the target has an API page and
  plain code elsewhere (private helpers, other libraries), so no role can break the strict build;
* simple tables (columns under ``====  ====`` rules): become Markdown tables;
* a paragraph ending in ``::`` before a literal block: keeps a single ``:`` (the block is already indented code).

The source files stay unchanged; this runs at build time only.
"""

from __future__ import annotations

import re
from typing import Any

from griffe import Alias, AliasResolutionError, CyclicAliasError, Extension, GriffeLoader, Module, NameResolutionError, Object

ROLE = re.compile(r":(?:class|func|meth|attr|mod|data|obj|exc|const):`(?P<body>[^`]+)`")
TITLED_TARGET = re.compile(r"^(?P<title>.+?)\s*<(?P<target>[^<>]+)>$")
TABLE_RULE = re.compile(r"^ *=+( +=+)+ *$")


def _resolve(obj: Object, loader: GriffeLoader, target: str) -> str | None:
    """The full path of ``target`` as written in ``obj``'s docstring, or None when it cannot be resolved."""
    try:
        member: Object | Alias = loader.modules_collection[target]  # a full dotted path of the loaded packages
    except (KeyError, ValueError):
        head, _, rest = target.partition(".")
        try:
            path = obj.resolve(head)
        except NameResolutionError:
            return None
        return f"{path}.{rest}" if rest else path
    if not isinstance(member, Alias):
        return str(member.path)
    try:
        return member.final_target.path
    except (AliasResolutionError, CyclicAliasError):  # an import from a package that is not loaded
        return member.target_path


def _roles_to_autorefs(text: str, obj: Object, loader: GriffeLoader) -> str:
    def replace(match: re.Match[str]) -> str:
        body = match["body"].strip()
        titled = TITLED_TARGET.match(body)
        if titled:
            title, target = titled["title"], titled["target"]
        else:
            target = body.lstrip("~")
            title = target.rsplit(".", 1)[-1] if body.startswith("~") else target
        path = _resolve(obj, loader, target)
        code = f"<code>{title}</code>"
        return code if path is None else f'<autoref optional identifier="{path}">{code}</autoref>'

    return ROLE.sub(replace, text)


def _table_to_markdown(lines: list[str]) -> list[str]:
    """A reST simple table (header rule, header, rule, body, closing rule) as Markdown table lines."""
    starts = [m.start() for m in re.finditer(r"=+", lines[0])]

    def cells(line: str) -> list[str]:
        bounds = [*starts, max(len(line), starts[-1]) + 1]
        return [line[bounds[i] : bounds[i + 1]].strip() for i in range(len(starts))]

    def merge(row: list[str], more: list[str]) -> list[str]:
        return [f"{old} {new}".strip() for old, new in zip(row, more, strict=True)]

    second_rule = next(i for i in range(1, len(lines)) if TABLE_RULE.match(lines[i]))
    header = [""] * len(starts)
    for line in lines[1:second_rule]:
        header = merge(header, cells(line))
    body: list[list[str]] = []
    for line in lines[second_rule + 1 : -1]:
        if not line.strip():
            continue
        values = cells(line)
        if body and not values[0]:
            body[-1] = merge(body[-1], values)  # a continuation line: the first column is empty
        else:
            body.append(values)
    pad = lines[0][: len(lines[0]) - len(lines[0].lstrip())]
    return [pad + "| " + " | ".join(row) + " |" for row in [header, ["---"] * len(starts), *body]]


def _tables_to_markdown(text: str) -> str:
    lines = text.split("\n")
    out: list[str] = []
    i = 0
    while i < len(lines):
        if TABLE_RULE.match(lines[i]):
            rules = [i]
            j = i + 1
            while j < len(lines) and len(rules) < 3 and lines[j].strip():
                if TABLE_RULE.match(lines[j]):
                    rules.append(j)
                j += 1
            if len(rules) == 3:  # header rule, header/body rule, closing rule
                out += _table_to_markdown(lines[i : rules[-1] + 1])
                i = rules[-1] + 1
                continue
        out.append(lines[i])
        i += 1
    return "\n".join(out)


def _literal_markers(text: str) -> str:
    text = re.sub(r"(?m)^[ \t]*::[ \t]*$", "", text)  # a bare "::" line introduces the block and disappears
    return re.sub(r"(?m)(\S)::[ \t]*$", r"\1:", text)  # "Example::" reads "Example:"


def markdown_docstring(text: str, obj: Object, loader: GriffeLoader) -> str:
    """``text`` with its reST roles, simple tables and literal-block markers turned into Markdown."""
    return _literal_markers(_tables_to_markdown(_roles_to_autorefs(text, obj, loader)))


class SphinxMarkup(Extension):
    """Rewrites every docstring of a loaded package once the whole package is known (so names resolve)."""

    def on_package(self, *, pkg: Module, loader: GriffeLoader, **kwargs: Any) -> None:
        pending: list[Object] = [pkg]
        while pending:
            obj = pending.pop()
            if obj.docstring is not None:
                obj.docstring.value = markdown_docstring(obj.docstring.value, obj, loader)
            pending += [member for member in obj.members.values() if not isinstance(member, Alias)]
