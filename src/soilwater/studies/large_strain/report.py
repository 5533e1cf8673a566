"""Large-strain consolidation against Gibson's solution in the report
(:mod:`soilwater.studies.large_strain.study`)."""

from pathlib import Path

from soilwater.studies.harness import tables
from soilwater.studies.large_strain import figures as strain_figures
from soilwater.studies.large_strain import study

NAME = "large-strain"


def run(root, inputs):
    """The tables ``large_strain_curves``, ``large_strain_small_strain``,
    ``large_strain``, ``large_strain_profiles`` and ``large_strain_profile_errors`` and
    the figures of :func:`figures`; returns ``{"large strain", "large strain small",
    "large strain profile errors", "large strain curves", "large strain profiles"}``."""
    curves = study.curves()
    small = study.small_strain(curves)
    summary = study.summary(curves)
    profiles = study.profiles()
    errors = study.profile_summary(profiles)
    for table, stem in ((curves, "large_strain_curves"), (small, "large_strain_small_strain"),
                        (summary, "large_strain"), (profiles, "large_strain_profiles"),
                        (errors, "large_strain_profile_errors")):
        tables.write(table, root / "tables" / stem)
    data = {"large strain": summary, "large strain small": small,
            "large strain profile errors": errors, "large strain curves": curves,
            "large strain profiles": profiles}
    figures(root, data)
    return data


def figures(root, data):
    """The figures ``large_strain`` (settlement against Gibson's) and
    ``large_strain_profiles`` (the loaded column's profiles) under ``root/figures``, from
    :func:`run`'s data; returns their paths."""
    folder = Path(root) / "figures"
    return [strain_figures.settlement(data["large strain curves"],
                                      data["large strain small"],
                                      folder / "large_strain.png"),
            strain_figures.profiles(data["large strain profiles"], study.CASES[0],
                                    folder / "large_strain_profiles.png")]


def section(data):
    """The section's markdown lines."""
    return study.section(data["large strain"], data["large strain small"],
                         data["large strain profile errors"])
