"""``twin serve``: the Monte Carlo robustness service (HTTP API, web page, durable registry).

A thin layer over the library, like the CLI: campaigns are validated by :func:`campaigns.load_spec`
and executed by :func:`app.pipeline.run_campaign_pipeline` (what ``twin campaign run --analyze
--report`` runs) in a runner subprocess per campaign. Modules:

* :mod:`app.service.registry` — the SQLite registry (campaigns, tokens) in the data directory;
* :mod:`app.service.auth` — bearer tokens with roles, and the browser's login cookie;
* :mod:`app.service.submission` — a submitted TOML spec validated and frozen into the data directory;
* :mod:`app.service.executor` — the queue: one runner subprocess at a time, requeue on start, cancel;
* :mod:`app.service.runner` — the subprocess that runs one campaign and records its progress;
* :mod:`app.service.api` — the versioned JSON API (``/api/v1``) and :mod:`app.service.web` — the web page;
* :mod:`app.service.command` — the ``twin serve`` subcommand.

See ``docs/service.md``.
"""
