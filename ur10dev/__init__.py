"""Development tools shared by the tests, the benchmarks and the scripts; not part of the installed app.

* :mod:`ur10dev.waiting` — waiting on a condition, never for a fixed time;
* :mod:`ur10dev.viser_client` — a headless client that speaks viser's protocol;
* :mod:`ur10dev.app_process` — the app in a process of its own, and the figures it reports;
* :mod:`ur10dev.browser` — Debian's headless Chromium, driven by playwright;
* :mod:`ur10dev.colour_vision` — colours as protan, deutan and washed-out eyes see them.

Run from a clone: pytest puts the clone's root on ``sys.path`` (``pythonpath`` in
pyproject.toml), and the benchmarks and scripts insert it themselves.
"""
