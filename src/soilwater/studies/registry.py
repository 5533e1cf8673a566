"""The studies of the report, in report order: name ->
:class:`~soilwater.studies.harness.study.Study`.

``soilwater report`` runs them all; ``soilwater report --only NAME[,NAME]`` reruns the
named ones and rebuilds REPORT.md from every study's last saved output.
"""

from soilwater.studies.harness.study import Study

STUDIES = {study.name: study for study in (
    Study("material", "soilwater.studies.peers.report"),
    Study("verification", "soilwater.studies.verification.report"),
    Study("uniqueness", "soilwater.studies.uniqueness.report"),
    Study("stability", "soilwater.studies.stability.report"),
    Study("consolidation", "soilwater.studies.consolidation.report"),
    Study("footing", "soilwater.studies.footing.report"),
    Study("footing-domain", "soilwater.studies.footing.domain_report"),
    Study("footing-fair", "soilwater.studies.footing_fair.report"),
    Study("footing-consolidation", "soilwater.studies.footing_consolidation.report"),
    Study("footing-pictures", "soilwater.studies.footing.pictures_report"),
    Study("shearband", "soilwater.studies.shearband.report"),
    Study("large-strain", "soilwater.studies.large_strain.report"),
    Study("embankment", "soilwater.studies.embankment.report"),
    Study("essential", "soilwater.studies.essential.report"),
)}
