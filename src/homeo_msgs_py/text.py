"""Text shown to a user that carries a value someone else chose (no imports: ``params`` and
``schemas`` both use it, and neither may import the other's module for it)."""

from __future__ import annotations


def one_line(text: str) -> str:
    """``text`` as a reason shows a value someone else chose: on one line, control characters
    (line breaks among them) escaped."""
    return text if text.isprintable() else "".join(c if c.isprintable() else repr(c)[1:-1] for c in text)
