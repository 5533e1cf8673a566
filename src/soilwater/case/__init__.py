"""Cases: the validated, immutable description of a problem that every method solves.

Start at :func:`soilwater.case.loader.load_case` (also :func:`soilwater.load_case`); its
module docstring maps the rest of the package.
"""
