"""The graph's own messages, signed (no rclpy).

DDS security is not in the PyPI wheels, so the graph protects itself: the launcher makes a
secret for one graph (``make_secret``), in a file only its user can read, and gives the nodes
the file's path in the environment (``HOMEO_AUTH_FILE``): never on a command line or in a
parameter, which anyone on the domain can list. Every message of the graph then ends with an
HMAC-SHA256 of its text::

    {"schema":"homeo/action",...,"stamp":1700000000.2,"auth":"<64 hex digits>"}

The signature covers every character before ``,"auth"`` (closed by ``}``), so checking it
needs no re-serialisation; the text stays one JSON object that ``ros2 topic echo``, a bag and
Foxglove show as it is. Readers drop unsigned and wrongly signed messages with a reason.
A person's topic (``homeo/human_input``) is not signed: a person types it.
See docs/SECURITY.md for what this does and does not protect.
"""

from __future__ import annotations

import hashlib
import hmac
import os
import secrets
import stat
import tempfile
from pathlib import Path

from .schemas import AUTH_KEY, Rejected

ENV = "HOMEO_AUTH_FILE"
_TAG = f',"{AUTH_KEY}":"'
_SIG_HEX = 64
_TAIL = len(_TAG) + _SIG_HEX + 2  # ,"auth":"<hex>"}


class AuthError(Exception):
    """The secret cannot be made or read (one line)."""


class Signer:
    """Signs and checks the graph's messages with one secret key."""

    def __init__(self, key: bytes):
        if len(key) < 16:
            raise AuthError("the graph's secret is shorter than 16 bytes")
        self._key = key

    def _mac(self, body: str) -> str:
        return hmac.new(self._key, body.encode("utf-8", "surrogatepass"), hashlib.sha256).hexdigest()

    def sign(self, text: str) -> str:
        """``text`` (one JSON object) with its signature as the last key."""
        return f"{text[:-1]}{_TAG}{self._mac(text)}\"}}"

    def verify(self, text: str) -> str:
        """The signed JSON text without its signature, or :class:`Rejected`."""
        if not isinstance(text, str) or len(text) < _TAIL + 2 or text[-_TAIL:-_SIG_HEX - 2] != _TAG \
                or not text.endswith('"}'):
            raise Rejected("unsigned message (this graph signs its messages; see docs/SECURITY.md)")
        body = text[:-_TAIL] + "}"
        if not hmac.compare_digest(text[-_SIG_HEX - 2:-2], self._mac(body)):
            raise Rejected("wrong signature (a message from outside this graph, or altered)")
        return body


def strip(text: str) -> str:
    """A signed message's JSON text without the signature, unchecked (tools that only read)."""
    if isinstance(text, str) and len(text) >= _TAIL + 2 and text[-_TAIL:-_SIG_HEX - 2] == _TAG:
        return text[:-_TAIL] + "}"
    return text


def make_secret() -> tuple[Path, Path]:
    """A fresh secret in a new private folder: ``(file, folder)``; the caller removes the folder."""
    folder = Path(tempfile.mkdtemp(prefix="homeo-auth-"))  # mode 0700
    path = folder / "graph.key"
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
    with os.fdopen(fd, "w") as fh:
        fh.write(secrets.token_hex(32))
    return path, folder


def load_signer(env=os.environ) -> Signer | None:
    """The graph's signer from ``HOMEO_AUTH_FILE`` (None: the graph runs without authentication).
    A file that others may read or write is refused: its secret would not be one."""
    name = env.get(ENV, "")
    if not name:
        return None
    try:
        st = os.stat(name)
        if st.st_mode & (stat.S_IRWXG | stat.S_IRWXO):
            raise AuthError(f"{ENV}={name} is readable or writable by others (chmod 600 it)")
        key = bytes.fromhex(Path(name).read_text().strip())
    except OSError as exc:
        raise AuthError(f"{ENV}={name}: {exc.strerror or exc}") from None
    except ValueError:
        raise AuthError(f"{ENV}={name} does not hold a hex secret") from None
    return Signer(key)
