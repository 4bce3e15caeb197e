"""The app's package data (link meshes), installed as ``app.assets`` (see pyproject.toml)."""
