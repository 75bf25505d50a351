"""The durable registry of a service: one SQLite file (WAL mode) in the data directory.

It holds every campaign accepted (its state, stage, progress, timings, spec hash, overrides, the
verdict statements of its analysis) and the access tokens (their SHA-256 only). The server and the
runner subprocesses write to it concurrently; WAL lets readers go on while one of them writes, and
every connection waits up to ``BUSY_TIMEOUT`` for a writer instead of failing.

Layout of the data directory::

    DIR/
      registry.sqlite3            this registry (+ -wal, -shm while open)
      campaigns/<id>/input/       the submitted spec, frozen at submission (spec.toml + what it extends)
      campaigns/<id>/out/         the campaign's output directory (chunks/, results.nc, analysis.nc, report.*)
      campaigns/<id>/runner.log   what the runner printed (stages, warnings, a traceback if it crashed)
      staging/                    specs being validated (removed at once; leftovers are removed on start)
"""

from __future__ import annotations

import json
import sqlite3
import threading
import time
from pathlib import Path

REGISTRY_NAME = "registry.sqlite3"
#: How long [s] a connection waits for another writer before giving up.
BUSY_TIMEOUT = 30.0
STATES = ("queued", "running", "done", "failed", "cancelled")
FINAL_STATES = ("done", "failed", "cancelled")
#: The states a campaign holds a place in the queue in (what the per-user limit counts).
ACTIVE_STATES = ("queued", "running")
_ACTIVE = "(" + ", ".join(f"'{state}'" for state in ACTIVE_STATES) + ")"  # as an SQL list

_SCHEMA = """
CREATE TABLE IF NOT EXISTS campaigns (
    seq INTEGER PRIMARY KEY AUTOINCREMENT,
    id TEXT UNIQUE NOT NULL,
    name TEXT NOT NULL,
    state TEXT NOT NULL,
    stage TEXT NOT NULL DEFAULT '',
    stage_message TEXT NOT NULL DEFAULT '',
    spec_hash TEXT NOT NULL,
    overrides TEXT NOT NULL DEFAULT '{}',
    submitted_by TEXT NOT NULL,
    submitted_at REAL NOT NULL,
    started_at REAL,
    finished_at REAL,
    runs_total INTEGER NOT NULL,
    runs_done INTEGER NOT NULL DEFAULT 0,
    failures TEXT NOT NULL DEFAULT '{}',
    failure_examples TEXT NOT NULL DEFAULT '[]',
    legs INTEGER NOT NULL DEFAULT 0,
    error TEXT NOT NULL DEFAULT '',
    summary TEXT NOT NULL DEFAULT '{}',
    cancel_requested INTEGER NOT NULL DEFAULT 0
);
CREATE TABLE IF NOT EXISTS tokens (
    name TEXT PRIMARY KEY,
    role TEXT NOT NULL,
    token_hash TEXT UNIQUE NOT NULL,
    created_at REAL NOT NULL
);
"""

_JSON_FIELDS = ("overrides", "failures", "failure_examples", "summary")


class Registry:
    """Access to the registry of data directory ``data``; one SQLite connection per thread.

    Parameters
    ----------
    data : Path
        The data directory (created if needed).
    """

    def __init__(self, data: str | Path):
        self.data = Path(data)
        self.data.mkdir(parents=True, exist_ok=True)
        self.path = self.data / REGISTRY_NAME
        self._local = threading.local()
        with self._connect() as db:
            db.execute("PRAGMA journal_mode=WAL")
            db.executescript(_SCHEMA)

    def _connect(self) -> sqlite3.Connection:
        db = getattr(self._local, "db", None)
        if db is None:
            # autocommit off, explicit transactions through the context manager (commit or roll back)
            db = sqlite3.connect(self.path, timeout=BUSY_TIMEOUT, check_same_thread=True)
            db.row_factory = sqlite3.Row
            db.execute("PRAGMA synchronous=FULL")  # an accepted campaign survives a power cut, not just a crash
            self._local.db = db
        return db

    def campaign_dir(self, campaign_id: str) -> Path:
        return self.data / "campaigns" / campaign_id

    # --- campaigns

    def add_campaign(self, campaign_id: str, name: str, spec_hash: str, runs_total: int, overrides: dict,
                     submitted_by: str, max_active: int | None = None) -> bool:
        """Record a campaign as queued (its input files are already in place); whether it was.

        ``max_active``: not if ``submitted_by`` has that many campaigns queued or running already. The count
        and the insert are one statement, so concurrent submissions cannot all pass the count.
        """
        with self._connect() as db:
            cursor = db.execute(
                "INSERT INTO campaigns (id, name, state, spec_hash, overrides, submitted_by, submitted_at, runs_total) "
                "SELECT ?, ?, 'queued', ?, ?, ?, ?, ? WHERE ? IS NULL OR (SELECT COUNT(*) FROM campaigns "
                f"WHERE submitted_by = ? AND state IN {_ACTIVE}) < ?",
                (campaign_id, name, spec_hash, json.dumps(overrides), submitted_by, time.time(), runs_total,
                 max_active, submitted_by, max_active),
            )
        return cursor.rowcount == 1

    def active_of(self, submitted_by: str) -> dict[str, int]:
        """How many campaigns ``submitted_by`` has in each of :data:`ACTIVE_STATES`."""
        rows = self._connect().execute(
            f"SELECT state, COUNT(*) AS n FROM campaigns WHERE submitted_by = ? AND state IN {_ACTIVE} "
            "GROUP BY state", (submitted_by,)).fetchall()
        return {state: 0 for state in ACTIVE_STATES} | {r["state"]: r["n"] for r in rows}

    def campaign(self, campaign_id: str) -> dict | None:
        row = self._connect().execute("SELECT * FROM campaigns WHERE id = ?", (campaign_id,)).fetchone()
        return _decoded(row) if row is not None else None

    def campaigns(self, limit: int = 200) -> list[dict]:
        """The latest ``limit`` campaigns, newest first."""
        rows = self._connect().execute("SELECT * FROM campaigns ORDER BY seq DESC LIMIT ?", (limit,)).fetchall()
        return [_decoded(r) for r in rows]

    def ids_in_state(self, *states: str) -> list[str]:
        """Ids of the campaigns in one of ``states``, oldest submission first."""
        marks = ",".join("?" * len(states))
        rows = self._connect().execute(f"SELECT id FROM campaigns WHERE state IN ({marks}) ORDER BY seq", states)
        return [r["id"] for r in rows.fetchall()]

    def update(self, campaign_id: str, **fields) -> None:
        """Set ``fields`` of a campaign (dicts and lists stored as JSON)."""
        fields = {k: json.dumps(v) if k in _JSON_FIELDS else v for k, v in fields.items()}
        assignments = ", ".join(f"{k} = ?" for k in fields)
        with self._connect() as db:
            db.execute(f"UPDATE campaigns SET {assignments} WHERE id = ?", (*fields.values(), campaign_id))

    def transition(self, campaign_id: str, from_states: tuple[str, ...], **fields) -> bool:
        """Set ``fields`` only if the campaign is in one of ``from_states``; whether it was."""
        fields = {k: json.dumps(v) if k in _JSON_FIELDS else v for k, v in fields.items()}
        assignments = ", ".join(f"{k} = ?" for k in fields)
        marks = ",".join("?" * len(from_states))
        with self._connect() as db:
            cursor = db.execute(f"UPDATE campaigns SET {assignments} WHERE id = ? AND state IN ({marks})",
                                (*fields.values(), campaign_id, *from_states))
        return cursor.rowcount == 1

    # --- tokens

    def add_token(self, name: str, role: str, token_hash: str) -> None:
        """Record a token; raises ``ValueError`` if the name is taken."""
        try:
            with self._connect() as db:
                db.execute("INSERT INTO tokens (name, role, token_hash, created_at) VALUES (?, ?, ?, ?)",
                           (name, role, token_hash, time.time()))
        except sqlite3.IntegrityError:
            raise ValueError(f"a token named {name!r} exists already; revoke it first or choose another name") from None

    def token_by_hash(self, token_hash: str) -> dict | None:
        row = self._connect().execute("SELECT name, role FROM tokens WHERE token_hash = ?", (token_hash,)).fetchone()
        return dict(row) if row is not None else None

    def tokens(self) -> list[dict]:
        rows = self._connect().execute("SELECT name, role, created_at FROM tokens ORDER BY name").fetchall()
        return [dict(r) for r in rows]

    def revoke_token(self, name: str) -> bool:
        with self._connect() as db:
            return db.execute("DELETE FROM tokens WHERE name = ?", (name,)).rowcount == 1


def _decoded(row: sqlite3.Row) -> dict:
    record = dict(row)
    for key in _JSON_FIELDS:
        record[key] = json.loads(record[key])
    return record
