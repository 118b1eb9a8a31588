"""The version of skysh, in one place (read by pyproject.toml and the file format)."""

__version__: str = "0.1.0"
