"""Run the Python blocks of a Markdown page and compare what they print with what their comments say.

The convention the docs follow (README.md, docs/tutorial.md): a ``print(...)`` statement's inline comment
is what it prints (its first line), and whole-line comments right after a statement that prints (a
``print`` or a loop around one) are the lines it prints next; a comment ending with ``...`` gives the
beginning of its line only.  Comments after statements that print nothing are explanations, not checked.
"""
from __future__ import annotations

import ast
import contextlib
import io
import re
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

#: every statement's captured output stream, kept alive for the whole process: CPython 3.11's print() holds a
#: *borrowed* reference to sys.stdout while it formats its arguments, so a background thread printing (the README's
#: ``start_branch(..., on_point=print)``) wrote into a freed StringIO once the next statement swapped sys.stdout and
#: dropped the last reference to it: a segfault in the job's thread (issue 52; tests/test_doc_blocks_threads.py)
_STREAMS = []


def python_blocks(page):
    """The ```python blocks of ``page`` (a path relative to the repository), as source strings."""
    return re.findall(r"^```python\n(.*?)^```", (ROOT / page).read_text(), flags=re.S | re.M)


def _prints(node):
    return any(isinstance(n, ast.Call) and isinstance(n.func, ast.Name) and n.func.id == "print"
               for n in ast.walk(node))


def expected_lines(lines, stmt):
    """What the comments say statement ``stmt`` (an ast node of the block whose source lines are ``lines``)
    prints: its inline comment (a print statement's) and the whole-line comments that follow it."""
    out = []
    last = lines[stmt.end_lineno - 1]
    if isinstance(stmt, ast.Expr) and "#" in last:
        code, _, comment = last.partition("  #")
        if comment.strip():
            out.append(comment.strip())
    k = stmt.end_lineno
    while k < len(lines) and lines[k].startswith("# "):
        out.append(lines[k][2:].rstrip())
        k += 1
    return out


def matches(printed, claimed):
    """True if the printed line is the claimed one (or begins with it, for a claim ending with '...')."""
    if claimed.endswith("..."):
        return printed.startswith(claimed[:-3].rstrip())
    return printed.rstrip() == claimed


def run_blocks(page, namespace=None, only=None):
    """Execute the Python blocks of ``page`` (those of indices ``only``, default all) one top-level
    statement at a time in one namespace, and check every printing statement's output against its
    comments (AssertionError naming the line otherwise).
    Returns (namespace, [(first source line, seconds)] of each statement)."""
    ns = {} if namespace is None else namespace
    times = []
    blocks = python_blocks(page)
    for block in (blocks if only is None else [blocks[k] for k in only]):
        lines = block.splitlines()
        for stmt in ast.parse(block).body:
            # the statement itself, not its whole line: `a(); b()` on one line is two statements, and
            # running the line once per statement ran a(); b() twice (a queue.get() then waited forever)
            src = ast.get_source_segment(block, stmt)
            buf = io.StringIO()
            _STREAMS.append(buf)
            t0 = time.perf_counter()
            with contextlib.redirect_stdout(buf):
                exec(compile(src, f"<{page}>", "exec"), ns)
            times.append((lines[stmt.lineno - 1], time.perf_counter() - t0))
            if not _prints(stmt) or "on_point=print" in src:
                continue
            printed = buf.getvalue().splitlines()
            claimed = expected_lines(lines, stmt)
            assert claimed, f"{page}: `{lines[stmt.lineno - 1]}` prints {printed[:3]} but no comment says what"
            assert len(printed) >= len(claimed) and all(matches(p, c) for p, c in zip(printed, claimed)), (
                f"{page}: `{lines[stmt.lineno - 1].strip()}` printed\n" + "\n".join(printed) +
                "\nwhile its comments say\n" + "\n".join(claimed))
    return ns, times
