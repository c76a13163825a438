"""A griffe extension used by the documentation build (mkdocs.yml): ddgjax's docstrings are
free-form Markdown written for the terminal, with lists that start right after a line of text:

    **Arguments:**
    - `tol`: ...

Python-Markdown starts a list only after a blank line, so the extension inserts one before the
first item of such a list (outside code blocks).  The source files are not changed.
"""

from __future__ import annotations

import re

import griffe

ITEM = re.compile(r"^(\s*)([-*+]|\d+\.)\s+\S")
FENCE = re.compile(r"^\s*(```|~~~)")


def separate_lists(text: str) -> str:
    """`text` with a blank line before every list item that follows a line of plain text."""
    out: list[str] = []
    in_fence = in_list = False
    for line in text.splitlines():
        if FENCE.match(line):
            in_fence = not in_fence
        elif not in_fence:
            blank = not line.strip()
            item = ITEM.match(line)
            previous = out[-1] if out else ""
            # an indented block after a blank line is code, unless it continues a list
            code = line.startswith("    ") and not previous.strip() and not in_list
            if item and not code and previous.strip() and not in_list:
                out.append("")
            if item:
                in_list = True
            elif not blank and not line.startswith(" ") and not previous.strip():
                in_list = False
        out.append(line)
    return "\n".join(out)


class MarkdownDocstrings(griffe.Extension):
    def on_instance(self, *, obj: griffe.Object, **kwargs) -> None:
        if obj.docstring is not None:
            obj.docstring.value = separate_lists(obj.docstring.value)
