"""Where the keys of the YAML files read so far are, for error messages.

`stl_lfd.yamlfile.read_yaml` records each file's keys (`remember`); a `ConfigError` whose
message names a file and a key, `FILE: 'a.b[2].c' ...`, is shown as `FILE:LINE:COLUMN: ...`
(`with_position`), at the key itself or, when the key is missing, at its nearest parent.
"""

from __future__ import annotations

import re
from collections import OrderedDict

REMEMBERED_FILES = 64  # the most recently read files are kept

# file as named in messages -> dotted key ('a.b[2].c') -> 1-based (line, column) of the key
_positions: OrderedDict[str, dict[str, tuple[int, int]]] = OrderedDict()
_MESSAGE_KEY = re.compile(r"^(?P<file>[^\n]+?): (?:(?:unknown |missing )?key )?'(?P<key>[^'\n]+)'")
_LAST_PART = re.compile(r"(\.[^.\[]*|\[\d+\])$")


def remember(file: str, positions: dict[str, tuple[int, int]]) -> None:
    """Keep `positions` (dotted key -> line, column) of `file`, named as messages name it."""
    _positions[file] = positions
    _positions.move_to_end(file)
    while len(_positions) > REMEMBERED_FILES:
        _positions.popitem(last=False)


def with_position(message: str) -> str:
    """`message` with the line and column of the key it names, when it is of the form
    `FILE: 'key' ...` (or `FILE: unknown key 'key' ...`) about a remembered file."""
    match = _MESSAGE_KEY.match(message)
    if match is None or match["file"] not in _positions:
        return message
    positions, key = _positions[match["file"]], match["key"]
    while key not in positions:
        shorter = _LAST_PART.sub("", key)
        if shorter == key or not shorter:
            return message
        key = shorter
    line, column = positions[key]
    return f"{match['file']}:{line}:{column}: {message[len(match['file']) + 2 :]}"
