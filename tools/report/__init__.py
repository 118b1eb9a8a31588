"""
The skysh error report, one module per section
==============================================

``tools/error_report.py`` is the command line; :mod:`report.run` chooses and runs
the sections and writes ``report.md``. Each ``sNN_*.py`` module is one section:
``compute(ctx)`` returns its data (plain dicts and arrays), ``render(ctx, data)``
writes its text, tables and figures. They share :mod:`report.common` (formatting,
figures, the one timing helper, small computations over the package's public
API), :mod:`report.data` (grids and the degree sweep, computed once per run),
:mod:`report.studies` (the sky-data studies, imported in one place) and
:mod:`report.plans` (the quick and full sizes).
"""
