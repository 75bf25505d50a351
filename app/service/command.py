"""``twin serve`` and ``twin serve token ...``: the service's command line (imports nothing heavy until it runs)."""

from __future__ import annotations

import logging
import os
import sys
from pathlib import Path

ROLES = ("read", "submit", "admin")


def add_serve_parser(sub) -> None:
    """Add ``serve`` to the ``twin`` command's subparsers."""
    serve = sub.add_parser("serve", help="the robustness service: HTTP API and web page over a campaign registry")
    serve.add_argument("--data", type=Path, help="data directory (registry, campaigns); created if needed (required)")
    serve.add_argument("--host", default="127.0.0.1", help="address to bind (default 127.0.0.1: this machine only)")
    serve.add_argument("--port", type=int, default=8765, help="port (default 8765)")
    serve.add_argument("--workers", type=int, default=2, help="worker processes of each campaign's local cluster")
    serve.add_argument("--scheduler", help="address of an existing dask scheduler (instead of a local cluster)")
    serve.add_argument("--max-campaign-hours", type=float, default=None,
                       help="refuse a campaign whose estimated duration is longer (default 24 h)")
    serve.add_argument("--max-queued-per-user", type=int, default=None,
                       help="campaigns one token may have queued or running at once (default 5)")
    serve.set_defaults(func=cmd_serve)
    serve_sub = serve.add_subparsers(dest="serve_command")
    token = serve_sub.add_parser("token", help="access tokens")
    token_sub = token.add_subparsers(dest="token_command", required=True)
    p = token_sub.add_parser("create", help="create a token and print it (once: only its hash is stored)")
    p.add_argument("name", help="who or what uses the token, e.g. alice or ci")
    p.add_argument("--role", choices=ROLES, required=True,
                   help="read: list and download; submit: also submit and cancel one's own; admin: also cancel any")
    p.set_defaults(func=cmd_token_create)
    p = token_sub.add_parser("list", help="list the tokens (names and roles)")
    p.set_defaults(func=cmd_token_list)
    p = token_sub.add_parser("revoke", help="revoke a token")
    p.add_argument("name")
    p.set_defaults(func=cmd_token_revoke)
    for parser in token_sub.choices.values():
        parser.add_argument("--data", type=Path, required=True, help="data directory of the service")


def cmd_serve(args) -> int:
    import uvicorn

    from app.service.server import Settings, create_app

    if args.data is None:
        raise SystemExit("twin serve: error: --data DIR is required (the registry and the campaigns live there)")
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(name)s %(levelname)s %(message)s")
    data = args.data.resolve()
    data.mkdir(parents=True, exist_ok=True)
    os.chdir(data)  # a bare name in a submitted spec that is no built-in one then names nothing of the server's
    limit = {} if args.max_campaign_hours is None else {"max_campaign_hours": args.max_campaign_hours}
    if args.max_campaign_hours is not None and not args.max_campaign_hours > 0:
        raise SystemExit(f"twin serve: error: --max-campaign-hours must be > 0, got {args.max_campaign_hours:g}")
    if args.max_queued_per_user is not None:
        if args.max_queued_per_user < 1:
            raise SystemExit(f"twin serve: error: --max-queued-per-user must be >= 1, got {args.max_queued_per_user}")
        limit["max_queued_per_user"] = args.max_queued_per_user
    app = create_app(Settings(data=data, workers=args.workers, scheduler=args.scheduler, **limit))
    if args.host not in ("127.0.0.1", "localhost", "::1"):
        logging.getLogger("benchtwin.service").warning(
            "listening on %s: reachable from other machines; tokens travel in clear unless a TLS proxy is in front",
            args.host)
    # access log: method, path (without its query string) and status; a token in a URL is refused
    uvicorn.run(app, host=args.host, port=args.port, log_level="info", timeout_graceful_shutdown=30)
    return 0


def _registry(args):
    from app.service.registry import Registry

    return Registry(args.data)


def cmd_token_create(args) -> int:
    from app.service.auth import create_token

    try:
        token = create_token(_registry(args), args.name, args.role)
    except ValueError as exc:  # a bad or taken name: the user's to fix, one line
        print(f"twin serve token create: error: {exc}", file=sys.stderr)
        return 2
    print(f"token {args.name!r} ({args.role}); shown once, only its hash is stored:")
    print(token)
    return 0


def cmd_token_list(args) -> int:
    for record in _registry(args).tokens():
        print(f"{record['name']}\t{record['role']}")
    return 0


def cmd_token_revoke(args) -> int:
    if not _registry(args).revoke_token(args.name):
        print(f"no token named {args.name!r}")
        return 1
    print(f"revoked {args.name!r}")
    return 0
