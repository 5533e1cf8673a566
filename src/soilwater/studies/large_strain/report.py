"""Large-strain consolidation against Gibson's solution in the report
(:mod:`soilwater.studies.large_strain.study`)."""

from soilwater.studies.harness import tables
from soilwater.studies.large_strain import study

NAME = "large-strain"


def run(root, inputs):
    """The tables ``large_strain_curves``, ``large_strain_small_strain``,
    ``large_strain``, ``large_strain_profiles`` and ``large_strain_profile_errors`` and
    the figures ``large_strain`` and ``large_strain_profiles``; returns ``{"large
    strain", "large strain small", "large strain profile errors"}``."""
    curves = study.curves()
    small = study.small_strain(curves)
    summary = study.summary(curves)
    profiles = study.profiles()
    errors = study.profile_summary(profiles)
    for table, stem in ((curves, "large_strain_curves"), (small, "large_strain_small_strain"),
                        (summary, "large_strain"), (profiles, "large_strain_profiles"),
                        (errors, "large_strain_profile_errors")):
        tables.write(table, root / "tables" / stem)
    study.figure(curves, small, root / "figures" / "large_strain.png")
    study.profile_figure(profiles, study.CASES[0], root / "figures" / "large_strain_profiles.png")
    return {"large strain": summary, "large strain small": small,
            "large strain profile errors": errors}


def section(data):
    """The section's markdown lines."""
    return study.section(data["large strain"], data["large strain small"],
                         data["large strain profile errors"])
