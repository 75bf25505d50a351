"""Access tokens: roles, creation, and the check of each request.

A token is ``bt_`` + 32 random bytes (:func:`secrets.token_urlsafe`), shown once when it is created;
the registry keeps only its SHA-256, so a copy of the data directory gives no access. A request
carries it as ``Authorization: Bearer <token>``; a browser carries it in the HttpOnly, SameSite=Strict
cookie set by the login form (``/login``), which page scripts cannot read and other sites cannot send.
Tokens never reach a log: they travel in headers or a form body, never in a URL.

Roles are ordered: ``read`` (list, status, files, pages) < ``submit`` (also submit campaigns and
cancel one's own) < ``admin`` (also cancel anyone's).
"""

from __future__ import annotations

import hashlib
import secrets
from urllib.parse import urlsplit

from app.service.registry import Registry

ROLES = ("read", "submit", "admin")
TOKEN_PREFIX = "bt_"
COOKIE_NAME = "benchtwin_token"
#: Methods that change something: a browser's cookie may authenticate them only from this site's own pages.
UNSAFE_METHODS = ("POST", "PUT", "PATCH", "DELETE")
#: Query parameters that would carry a token in a URL (refused: URLs end up in logs, histories and Referer headers).
TOKEN_PARAMETERS = ("token", "access_token", "bearer", "api_key")


class AuthError(Exception):
    """A request without a valid token (401) or with too small a role (403)."""

    def __init__(self, status: int, message: str):
        super().__init__(message)
        self.status = status


def token_hash(token: str) -> str:
    return hashlib.sha256(token.encode()).hexdigest()


def create_token(registry: Registry, name: str, role: str) -> str:
    """Create a token named ``name`` with ``role``; return it (the only time it exists in clear).

    Raises
    ------
    ValueError
        One line naming what is wrong: the role, the name (empty, too long, not printable) or a name already taken.
    """
    if role not in ROLES:
        raise ValueError(f"role must be one of {', '.join(ROLES)}, got {role!r}")
    if not name or not name.isprintable() or len(name) > 100:
        shown = repr(name) if len(name) <= 100 else f"of {len(name)} characters"
        raise ValueError(f"token name {shown}: a token name is 1-100 printable characters (no newline, tab or "
                         "other control character)")
    token = TOKEN_PREFIX + secrets.token_urlsafe(32)
    registry.add_token(name, role, token_hash(token))
    return token


def identify(registry: Registry, authorization: str | None, cookie: str | None) -> dict:
    """The token record (``name``, ``role``) of a request.

    Raises
    ------
    AuthError
        401 if no token is given or it is unknown (or revoked).
    """
    token = None
    if authorization:
        scheme, _, value = authorization.partition(" ")
        if scheme.lower() != "bearer" or not value.strip():
            raise AuthError(401, "the Authorization header must be 'Bearer <token>'")
        token = value.strip()
    elif cookie:
        token = cookie
    if not token:
        raise AuthError(401, "a token is required (Authorization: Bearer <token>); create one with "
                             "`twin serve token create NAME --role read|submit|admin --data DIR`")
    record = registry.token_by_hash(token_hash(token))
    if record is None:
        raise AuthError(401, "unknown or revoked token")
    return record


def require(record: dict, role: str) -> None:
    """Raise a 403 :class:`AuthError` unless ``record``'s role is at least ``role``."""
    if ROLES.index(record["role"]) < ROLES.index(role):
        raise AuthError(403, f"this needs the {role!r} role; token {record['name']!r} has {record['role']!r}")


def cross_site(headers, *, strict: bool = True) -> str | None:
    """Why a browser request is not from this site's own pages, or None when it is.

    The browser says where a request comes from in headers a page cannot forge: ``Sec-Fetch-Site`` (every
    current browser) and ``Origin`` (every browser on a POST). A request is same-origin when
    ``Sec-Fetch-Site`` is ``same-origin``, or, without it, when ``Origin`` names this server (its ``Host``).
    ``strict``: a request with neither header is refused too (a cookie request that no browser made: scripts
    authenticate with ``Authorization: Bearer`` and are not concerned).
    """
    fetch_site = headers.get("sec-fetch-site")
    if fetch_site is not None:
        return None if fetch_site == "same-origin" else f"Sec-Fetch-Site: {fetch_site}"
    origin = headers.get("origin")
    if origin is None:
        return "neither Origin nor Sec-Fetch-Site says it comes from this site" if strict else None
    if origin == "null" or urlsplit(origin).netloc != headers.get("host"):
        return f"Origin: {origin}"
    return None
