"""The material section: the paper's Table 1, the stress-point driver's undrained paths
against the closed forms and the single-point peer data."""

from soilwater.studies.harness import tables
from soilwater.studies.peers import figures
from soilwater.studies.peers.study import summary

NAME = "material"


def run(root, inputs):
    """Table 1 and the peer table (``tables/table1``, ``tables/peer_single_point``) and
    the driver's figure; returns ``{"table1", "peers"}``."""
    data = {"table1": tables.table1(), "peers": summary()}
    tables.write(data["table1"], root / "tables" / "table1")
    tables.write(data["peers"], root / "tables" / "peer_single_point")
    figures.stress_paths_driver(root / "figures" / "stress_paths_driver.png")
    return data


def section(data):
    """The section's markdown lines."""
    return [
        "## Material (Table 1) and the theoretical solution",
        "",
        tables.to_markdown(data["table1"]),
        "![driver](figures/stress_paths_driver.png)",
        "",
        "The stress-point driver integrates the finite-strain Cam-clay rate equations "
        "under the paper's uniform stretching; its undrained paths lie on the closed "
        "forms (circles). Single-point peer data, with the tolerance of a different "
        "model variant:",
        "",
        tables.to_markdown(data["peers"]),
    ]
