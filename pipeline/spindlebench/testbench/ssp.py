"""``spindlebench export-ssp``: the FMU, a machine's parameter set and a scenario as an SSP file.

An SSP 1.0 archive (System Structure and Parameterization, Modelica Association) that other
tools open without spindlebench::

    SystemStructure.ssd            one system, one component (the FMU), its connectors wired
                                   to the system's; two parameter bindings
    resources/SpindleBench.fmu     the FMU (both interfaces; SSP tools step co-simulation)
    resources/<machine>.ssv        the machine's parameters (scenarios/machines/<NAME>.toml)
    resources/<scenario>.ssv       the scenario's parameters, cooling settings and the start
                                   value of every state (its initial state: cold, soak, ...)
    resources/<scenario>_inputs.csv  the four inputs at every communication point
    resources/provenance.json

SSP 1.0 has no element for input time series, so the inputs CSV is named by an annotation
(``org.spindlebench.inputs``) of the system; its columns are the system's input connectors.
The XML is written here (fixed order, no time stamps: the same inputs give the same bytes) and
checked against the SSP 1.0 schemas that pyssp-standard ships, then read back with it.
"""

from __future__ import annotations

import io
import json
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path

import numpy as np

from spindlebench.core import atomic
from spindlebench.core.errors import SpindlebenchError
from spindlebench.core.provenance import file_entry, provenance

SSD_NS = "http://ssp-standard.org/SSP1/SystemStructureDescription"
SSC_NS = "http://ssp-standard.org/SSP1/SystemStructureCommon"
SSV_NS = "http://ssp-standard.org/SSP1/SystemStructureParameterValues"
COMPONENT = "SpindleBench"
INPUTS_ANNOTATION = "org.spindlebench.inputs"
ZIP_DATE = (1980, 1, 1, 0, 0, 0)

for prefix, uri in (("ssd", SSD_NS), ("ssc", SSC_NS), ("ssv", SSV_NS)):
    ET.register_namespace(prefix, uri)


def _q(ns: str, tag: str) -> str:
    return f"{{{ns}}}{tag}"


def parameter_set(name: str, values: dict[str, float]) -> bytes:
    """An SSV file: one Real parameter per value, in the order given."""
    root = ET.Element(_q(SSV_NS, "ParameterSet"), version="1.0", name=name)
    parameters = ET.SubElement(root, _q(SSV_NS, "Parameters"))
    for key, value in values.items():
        parameter = ET.SubElement(parameters, _q(SSV_NS, "Parameter"), name=key)
        ET.SubElement(parameter, _q(SSV_NS, "Real"), value=repr(float(value)))
    return _xml_bytes(root)


def system_structure(name: str, inputs: list[str], outputs: list[str], bindings: list[str],
                     inputs_csv: str | None, stop_s: float | None) -> bytes:
    """The SSD: the system's connectors, the FMU component bound to ``bindings`` (SSV paths),
    every system input wired to the FMU's input of the same name and every FMU output out."""
    root = ET.Element(_q(SSD_NS, "SystemStructureDescription"), version="1.0", name=name)
    system = ET.SubElement(root, _q(SSD_NS, "System"), name=name)

    def connectors(parent: ET.Element) -> None:
        element = ET.SubElement(parent, _q(SSD_NS, "Connectors"))
        for kind, names in (("input", inputs), ("output", outputs)):
            for connector in names:
                c = ET.SubElement(element, _q(SSD_NS, "Connector"), name=connector, kind=kind)
                ET.SubElement(c, _q(SSC_NS, "Real"))

    connectors(system)
    elements = ET.SubElement(system, _q(SSD_NS, "Elements"))
    component = ET.SubElement(elements, _q(SSD_NS, "Component"), name=COMPONENT,
                              type="application/x-fmu-sharedlibrary",
                              source=f"resources/{COMPONENT}.fmu")
    connectors(component)
    if bindings:
        holder = ET.SubElement(component, _q(SSD_NS, "ParameterBindings"))
        for source in bindings:
            ET.SubElement(holder, _q(SSD_NS, "ParameterBinding"), source=source)
    wires = ET.SubElement(system, _q(SSD_NS, "Connections"))
    for connector in inputs:
        ET.SubElement(wires, _q(SSD_NS, "Connection"), startConnector=connector,
                      endElement=COMPONENT, endConnector=connector)
    for connector in outputs:
        ET.SubElement(wires, _q(SSD_NS, "Connection"), startElement=COMPONENT,
                      startConnector=connector, endConnector=connector)
    if inputs_csv is not None:
        annotations = ET.SubElement(system, _q(SSD_NS, "Annotations"))
        annotation = ET.SubElement(annotations, _q(SSC_NS, "Annotation"),
                                   type=INPUTS_ANNOTATION)
        ET.SubElement(annotation, "inputs", source=inputs_csv)
    if stop_s is not None:
        ET.SubElement(root, _q(SSD_NS, "DefaultExperiment"), startTime="0.0",
                      stopTime=repr(float(stop_s)))
    return _xml_bytes(root)


def _xml_bytes(root: ET.Element) -> bytes:
    ET.indent(root, space="  ")
    return b'<?xml version="1.0" encoding="UTF-8"?>\n' + ET.tostring(root, encoding="utf-8",
                                                                       xml_declaration=False)


def _inputs_csv(time_s: np.ndarray, columns: dict[str, np.ndarray]) -> bytes:
    out = io.StringIO()
    out.write(",".join(["time", *columns]) + "\n")
    for k, t in enumerate(time_s):
        out.write(",".join([repr(float(t)), *(repr(float(v[k])) for v in columns.values())])
                  + "\n")
    return out.getvalue().encode()


def export_ssp(machine: str, scenario_path: str | Path | None, out_path: str | Path,
               fmu_path: str | Path | None = None) -> Path:
    """Write the SSP for ``machine`` (and ``scenario_path``) to ``out_path``, atomically."""
    from spindlebench.core.paths import DEFAULT_FMU
    from spindlebench.machines.variants import load_machine
    from spindlebench.testbench.drivers import INPUT_NAMES, drive
    from spindlebench.testbench.runner import (
        check_machine,
        initial_state,
        inspect_fmu,
        parameter_values,
    )
    from spindlebench.testbench.scenario import load_scenario, start_state, with_machine

    out_path = Path(out_path)
    if out_path.suffix != ".ssp":
        raise SpindlebenchError(f"-o {out_path}: an SSP file name ends in .ssp")
    fmu_path = Path(DEFAULT_FMU if fmu_path is None else fmu_path)
    info = inspect_fmu(fmu_path)
    if info.model_description.coSimulation is None:
        raise SpindlebenchError(f"{fmu_path}: has no co-simulation interface, which SSP tools "
                                "step (rebuild it with `spindlebench build`)")
    chosen = load_machine(machine)
    check_machine(chosen, info.parameters, fmu_path.name)
    outputs = list(info.output_names)
    files: dict[str, bytes] = {f"resources/{COMPONENT}.fmu": fmu_path.read_bytes()}
    machine_ssv = f"resources/{chosen.name}.ssv"
    files[machine_ssv] = parameter_set(chosen.name, dict(chosen.parameters))
    bindings, inputs_csv, stop_s = [machine_ssv], None, None
    record: dict = {"machine": chosen.provenance()}
    if scenario_path is not None:
        scenario = with_machine(load_scenario(scenario_path), machine)
        signals = drive(scenario)
        values = {k: v for k, v in parameter_values(scenario, info).items()
                  if k not in chosen.parameters or scenario.parameters.get(k) is not None}
        x0 = initial_state(scenario, info, float(signals.ambient_C[0]), start_state(scenario))
        values.update(x0)
        scenario_ssv = f"resources/{scenario.name}.ssv"
        files[scenario_ssv] = parameter_set(scenario.name, values)
        bindings.append(scenario_ssv)
        inputs_csv = f"resources/{scenario.name}_inputs.csv"
        files[inputs_csv] = _inputs_csv(signals.time_s,
                                        {n: getattr(signals, n) for n in INPUT_NAMES})
        stop_s = scenario.duration_s
        record["scenario"] = file_entry(scenario_path)
    name = f"{COMPONENT}_{chosen.name}"
    files["SystemStructure.ssd"] = system_structure(name, list(INPUT_NAMES), outputs, bindings,
                                                    inputs_csv, stop_s)
    files["resources/provenance.json"] = (json.dumps(provenance(
        command="spindlebench export-ssp", fmu=file_entry(fmu_path), **record), indent=1)
        + "\n").encode()
    check_ssp_files(files)
    with atomic.atomic_path(out_path) as tmp, zipfile.ZipFile(tmp, "w") as archive:
        for member in sorted(files):
            entry = zipfile.ZipInfo(member, date_time=ZIP_DATE)
            entry.compress_type = zipfile.ZIP_DEFLATED
            entry.external_attr = 0o644 << 16
            archive.writestr(entry, files[member])
    return out_path


def check_ssp_files(files: dict[str, bytes]) -> None:
    """Validate the SSD and SSV files against the SSP 1.0 schemas pyssp-standard ships."""
    import pyssp_standard
    import xmlschema

    schemas = Path(pyssp_standard.__file__).parent / "resources"
    for member, data in files.items():
        schema = {".ssd": "SystemStructureDescription.xsd",
                  ".ssv": "SystemStructureParameterValues.xsd"}.get(Path(member).suffix)
        if schema is None:
            continue
        try:
            xmlschema.XMLSchema10(str(schemas / schema)).validate(io.BytesIO(data))
        except xmlschema.XMLSchemaValidationError as exc:
            raise SpindlebenchError(f"{member}: not valid SSP 1.0 ({exc.reason})") from None
