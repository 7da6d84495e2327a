"""scripts/paraview/pv_views.py reads what demos/coulomb3d.py writes (no ParaView needed).

The script lists its files (``SOURCES``) and fields (``FIELDS``) in one place; this
test checks that list against a fresh demo result: for each dataset the first
existing file holds every required field, by the script's own name matching.
"""

from __future__ import annotations

import importlib.util
import pathlib
import xml.etree.ElementTree as ET

from mpi4py import MPI

import pytest

SCRIPT = pathlib.Path(__file__).resolve().parent.parent / "scripts" / "paraview" / "pv_views.py"


@pytest.fixture(scope="module")
def pv_views():
    spec = importlib.util.spec_from_file_location("pv_views", SCRIPT)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)  # imports ParaView only inside its functions
    return module


def field_names(path: pathlib.Path) -> list[str]:
    """Names of the fields in an XDMF file or a VTX (.bp) directory."""
    if path.suffix == ".xdmf":
        return [a.get("Name") for a in ET.parse(path).getroot().iter("Attribute")]
    import adios2

    with adios2.FileReader(str(path)) as reader:
        vtk_xml = reader.available_attributes()["vtk.xml"]["Value"].strip('"')
    return [a.get("Name") for a in ET.fromstring(vtk_xml).iter("DataArray") if a.get("Name")]


def test_field_matches(pv_views):
    for found in ("von_mises", "von_mises [Pa]", "von_mises (Pa)", "von_mises_Pa"):
        assert pv_views.field_matches(found, "von_mises")
    for found in ("von_mises_max", "von", "displacement [m]", "von_mises [kg]"):
        assert not pv_views.field_matches(found, "von_mises")


def test_demo_output_has_the_fields(pv_views, load_demo, mpi_tmp_path):
    out = mpi_tmp_path / "coulomb"
    assert load_demo("coulomb3d").main(["--lev", "1", "--output", str(out), "--no-plot"]) == 0
    MPI.COMM_WORLD.Barrier()
    for role, candidates in pv_views.SOURCES.items():
        files = [out / name for name in candidates if (out / name).exists()]
        assert files, f"none of {candidates} written"
        names = [n for path in files for n in field_names(path)]
        for field, (dataset, required, *_) in pv_views.FIELDS.items():
            if dataset == role and required:
                assert any(pv_views.field_matches(n, field) for n in names), (field, names)


def test_state_names(pv_views):
    """The legend uses the contact-state names of the package's own output."""
    from contactqvi.contact.postprocess import STATE_NAMES

    assert {int(state): name for state, name in STATE_NAMES.items()} == {
        state: label for state, (label, _) in pv_views.CONTACT_STATES.items()
    }
