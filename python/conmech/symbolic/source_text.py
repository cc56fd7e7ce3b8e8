"""User strings in generated Fortran, and the check of a generated source.

Every string a user gives (symbol, coordinate, parameter, body and joint names, file names)
reaches the generated Fortran only through these helpers: in a comment as printable ASCII on
one line (:func:`comment_text`, :func:`comment_lines`), in data as a character constant built
from plain characters and achar() codes (:func:`string_constant`). :func:`check_source` then
refuses any source with a character outside printable ASCII, an over-long line, or a procedure
or C name that is not one of the expected entry points, whatever produced it.
"""
import re


_PLAIN = frozenset("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789"
                   "_ .,:;+-=()[]")


def comment_text(text, limit=60):
    """`text` as it may follow '!' in generated Fortran: one line of printable ASCII, every
    other character (newlines, quotes and '&' included, for the reader's sake) written as a
    \\x, \\u or \\U escape, cut to `limit` characters with '...'."""
    out = []
    for ch in str(text):
        o = ord(ch)
        if ch in _PLAIN or (32 < o < 127 and ch not in "\\\"'&!"):
            out.append(ch)
        elif o < 256:
            out.append(f"\\x{o:02x}")
        elif o < 65536:
            out.append(f"\\u{o:04x}")
        else:
            out.append(f"\\U{o:08x}")
    s = "".join(out)
    return s if len(s) <= limit else s[:limit - 3] + "..."


def comment_lines(text, prefix="!! ", width=96):
    """Comment lines (each starting with `prefix`, at most `width` characters) holding
    `text`, which must already be made safe by :func:`comment_text`."""
    if any(not (32 <= ord(c) < 127) for c in text):
        raise ValueError("comment_lines: text must be printable ASCII (use comment_text)")
    words, lines, cur = text.split(" "), [], ""
    room = width - len(prefix)
    for w in words:
        while len(w) > room:                  # an escaped name longer than a line
            if cur:
                lines.append(prefix + cur)
                cur = ""
            lines.append(prefix + w[:room])
            w = w[room:]
        if cur and len(cur) + 1 + len(w) > room:
            lines.append(prefix + cur)
            cur = w
        else:
            cur = (cur + " " + w) if cur else w
    if cur:
        lines.append(prefix + cur)
    return lines


def string_constant(text, indent="            "):
    """Lines of a Fortran character constant expression equal to the UTF-8 bytes of
    `text`: letters, digits, blanks and a few punctuation marks in quoted chunks, every
    other byte as achar(code), joined by // with free-form continuations."""
    parts, chunk = [], ""
    for b in str(text).encode("utf-8"):
        ch = chr(b)
        if b < 128 and ch in _PLAIN:
            chunk += ch
            if len(chunk) >= 48:
                parts.append(f'"{chunk}"')
                chunk = ""
        else:
            if chunk:
                parts.append(f'"{chunk}"')
                chunk = ""
            parts.append(f"achar({b})")
    if chunk or not parts:
        parts.append(f'"{chunk}"')
    lines, cur = [], ""
    for k, p in enumerate(parts):
        piece = p + ("//" if k < len(parts) - 1 else "")
        if cur and len(cur) + len(piece) > 72:
            lines.append(indent + cur + " &")
            cur = piece
        else:
            cur += piece
    lines.append(indent + cur)
    return lines


_PROC = re.compile(r"^\s*(?:(?:pure|elemental|recursive|impure|module|real\s*\([^)]*\)|"
                   r"integer(?:\s*\([^)]*\))?|logical|double\s+precision)\s+)*"
                   r"(subroutine|function|entry)\s+(\w+)", re.IGNORECASE)


_BIND = re.compile(r"bind\s*\(\s*c\s*(?:,\s*name\s*=\s*([\"'])([^\"']*)\1\s*)?\)",
                   re.IGNORECASE)


_END_PROC = re.compile(r"^\s*end\s+(subroutine|function)\b", re.IGNORECASE)


def _code_part(line):
    """The line without its comment (strings of generated code hold no '!': see
    string_constant)."""
    k = line.find("!")
    return line if k < 0 else line[:k]


_TREE_PROC = re.compile(r"^\s*(?:pure\s+)?subroutine\s+(tree_[a-z0-9_]+)\s*\(",
                        re.I | re.M)


def _c_names(entries, model_values):
    """The C names a generated module binds: its entry points, and the model-library
    description when it has default parameter values."""
    names = [f"conmech_{e}" for e in entries]
    if model_values is not None:
        names += ["conmech_model_info", "conmech_model_params", "conmech_model_param_names"]
    return names


def private_procedures(entries, source=None):
    """The internal (private, not C-bound) procedures the generated module defines beside
    the entry points `entries`: the body that the quadruple-precision Taylor entry wraps,
    and, given the `source` of a recursive tree, its passes (``tree_pos``, ``tree_vel``,
    ... and their pieces: names the generator makes, never from user strings)."""
    out = [f"conmech_{e}_body" for e in entries if e.endswith("taylor_qp")]
    if source is not None:
        out += sorted({m.lower() for m in _TREE_PROC.findall(source)})
    return out


def check_source(src, procedures, c_names=None, max_line=132):
    """ValueError unless the generated source `src` is printable ASCII (plus newlines) with
    lines of at most `max_line` characters, defines exactly the procedures named in
    `procedures` (no other subroutine, function or entry), and binds to C only the names
    in `c_names` (default: the procedure names); a last line of defence against a user
    string reaching the code unescaped."""
    allowed = {p.lower() for p in procedures}
    c_allowed = set(procedures if c_names is None else c_names)
    seen = []
    for k, line in enumerate(src.split("\n"), 1):
        bad = [c for c in line if not 32 <= ord(c) < 127]
        if bad:
            raise ValueError(f"generated Fortran line {k} holds the character {bad[0]!r}: "
                             "a user string reached the code unescaped")
        if len(line) > max_line:
            raise ValueError(f"generated Fortran line {k} is longer than {max_line} "
                             "characters")
        code = _code_part(line)
        if _END_PROC.match(code):
            continue
        m = _PROC.match(code)
        if m:
            name = m.group(2).lower()
            if name not in allowed:
                raise ValueError(f"generated Fortran line {k} defines an unexpected "
                                 f"procedure '{m.group(2)}'")
            seen.append(name)
        for b in _BIND.finditer(code):
            if not m or b.group(2) is None or b.group(2) not in c_allowed:
                raise ValueError(f"generated Fortran line {k} binds an unexpected C name "
                                 f"{b.group(2)!r}")
    if sorted(seen) != sorted(allowed):
        raise ValueError("generated Fortran defines the procedures "
                         f"{sorted(seen)}, expected {sorted(allowed)}")
