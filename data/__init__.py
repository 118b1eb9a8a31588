"""Shipped coefficient files of skysh (installed as the ``skysh.data`` package)."""
