"""
Studies of the library on sky data, kept out of the library
===========================================================

The package ``skysh`` holds algorithms; the experiments that measure them on the
Preetham sky live here, as colour-science keeps its plotting out of its models.
Nothing in ``skysh`` imports this package (``tests/test_layers.py`` checks it).

-   :mod:`studies.sky`: sky points spread over the fitted domain and their SH,
    from the shipped runtime or the reference projection (named, never a silent
    fallback).
-   :mod:`studies.quantize_study`: the Table 3 of Wiederien and Sloan (2024,
    seed 002) on sky data, with :func:`skysh.post.quantize.table3_errors`.
-   :mod:`studies.hazel_study`: the sky's exact irradiance and the accuracy of
    linear L1, Geomerics' non-linear L1, L2 and deringed L2 against it (seed 003).

``tools/`` must be on ``sys.path`` (scripts in ``tools/`` have it as their own
folder; the error report and the tests insert it): ``from studies import hazel_study``.
``tools/quantize_experiment.py`` prints both studies.
"""
