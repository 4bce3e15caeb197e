"""The app's package data (link meshes), installed as ``ur10teach.assets`` (see pyproject.toml)."""
