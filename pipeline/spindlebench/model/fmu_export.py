"""Explicit ODE → FMI 3.0 model-exchange FMU through ``casadi.DaeBuilder``, with repairs.

CasADi's FMU exporter is experimental. What we repair after ``export_fmu``:
- internal helper variables ``__assign__<name>__`` (illegal under the structured naming
  convention, never read by the C code) are removed from modelDescription.xml;
- states get ``initial="exact"`` and their start value, so an importer can set the initial
  state by name before initialisation (the wrapper's ``fmi3SetFloat64`` writes straight into
  the variable memory and ``fmi3EnterInitializationMode`` only sets the time);
- every unit used gets a ``<UnitDefinitions>`` entry in SI base units;
- ``<InitialUnknown>`` lists every output and state derivative (dependencies omitted = all);
- ``fmi3GetEventIndicators`` returns ``fmi3OK`` instead of ``fmi3Fatal`` for a model without
  event indicators (the C source is patched, then compiled by us);
- every state the importer does not set before ``fmi3EnterInitializationMode`` starts at the
  tunable parameter ``T_start`` (the wrapper records which states were set), so an FMPy user
  gets a cold start at 8 degC with ``start_values={"T_start": 281.15}`` alone;
- ``fmi3SetFloat64`` finds a state by a value-reference table, not a scan of all states;
- co-simulation (``fmi3InstantiateCoSimulation``, ``fmi3DoStep``) and saved states
  (``fmi3Get/SetFMUState``, serialisation) from ``fmu_extensions.c``, spliced into the
  wrapper; the model description gets ``<CoSimulation>`` and the capability flags;
- CVode callbacks in C (``sb_cvode_setup/table/rhs/stop``, extra exported symbols, which FMI
  allows; nothing in the model description) from the same file, so the runner's CVode calls
  the model without a Python callback (``testbench.native_cvode``);
- the archive is reproducible: no generation timestamp, an instantiation token derived from
  the sources, fixed zip dates and sorted entries.
"""

from __future__ import annotations

import hashlib
import math
import os
import platform
import shlex
import shutil
import subprocess
import tempfile
import xml.etree.ElementTree as ET
import zipfile
from importlib import metadata
from pathlib import Path

import casadi as ca

from spindlebench.core import atomic
from spindlebench.core.errors import SpindlebenchError
from spindlebench.core.names import KELVIN_OFFSET
from spindlebench.model import FMU_NAME
from spindlebench.model.equations import ExplicitOde

DEFAULT_COMPILER = "gcc"
ZIP_DATE = (1980, 1, 1, 0, 0, 0)
DEFAULT_STOP_TIME_S = 4 * 3600.0

# SI base-unit exponents (and factor/offset) of every unit the Modelica model may use.
UNIT_DEFINITIONS: dict[str, dict[str, float]] = {
    "1": {},
    "K": {"K": 1},
    "degC": {"K": 1, "offset": KELVIN_OFFSET},
    "K/s": {"K": 1, "s": -1},
    "1/K": {"K": -1},
    "W": {"kg": 1, "m": 2, "s": -3},
    "J/K": {"kg": 1, "m": 2, "s": -2, "K": -1},
    "W/K": {"kg": 1, "m": 2, "s": -3, "K": -1},
    "W/(m2.K)": {"kg": 1, "s": -3, "K": -1},
    "m": {"m": 1},
    "m2": {"m": 2},
    "um": {"m": 1, "factor": 1e-6},
    "urad": {"rad": 1, "factor": 1e-6},
    "1/m": {"m": -1},
    "W/m2": {"kg": 1, "s": -3},
    "N": {"kg": 1, "m": 1, "s": -2},
    "N/K": {"kg": 1, "m": 1, "s": -2, "K": -1},
    "N.m": {"kg": 1, "m": 2, "s": -2},
    "mm2/s": {"m": 2, "s": -1, "factor": 1e-6},
    "rev/min": {"rad": 1, "s": -1, "factor": 2 * math.pi / 60},
    "mm/min": {"m": 1, "s": -1, "factor": 1e-3 / 60},
    "W.min/mm": {"kg": 1, "m": 1, "s": -2, "factor": 60000.0},
}
BASE_UNIT_ORDER = ("kg", "m", "s", "A", "K", "mol", "cd", "rad", "factor", "offset")


def find_compiler() -> list[str]:
    """The C compiler command (``CC`` or gcc), or a one-line error if there is none."""
    command = shlex.split(os.environ.get("CC", "") or DEFAULT_COMPILER)
    if not command or shutil.which(command[0]) is None:
        name = command[0] if command else "(empty CC)"
        raise SpindlebenchError(
            f"no C compiler: '{name}' is not on PATH; the FMU build compiles the model "
            "binary with gcc (install gcc, or set CC to a C compiler)"
        )
    return command


def platform_tuple() -> tuple[str, str]:
    """FMI 3.0 platform folder name and shared-library suffix of this machine."""
    machine = {"amd64": "x86_64", "arm64": "aarch64"}.get(
        platform.machine().lower(), platform.machine().lower()
    )
    system = platform.system().lower()
    if system == "linux":
        return f"{machine}-linux", ".so"
    if system == "darwin":
        return f"{machine}-darwin", ".dylib"
    raise SpindlebenchError(
        f"building the FMU binary on {platform.system()} is not supported; the FMU "
        "sources can be compiled by the importer (fmpy compile)"
    )


def _dae_builder(ode: ExplicitOde) -> ca.DaeBuilder:
    dae = ca.DaeBuilder(FMU_NAME)

    def attrs(name: str, **extra: float) -> dict:
        info: dict = dict(extra)
        if ode.units.get(name):
            info["unit"] = ode.units[name]
        if ode.descriptions.get(name):
            info["description"] = ode.descriptions[name]
        minimum, maximum = ode.bounds.get(name, (None, None))
        if minimum is not None:
            info["min"] = minimum
        if maximum is not None:
            info["max"] = maximum
        return info

    p = [
        dae.add(name, "parameter", "tunable", attrs(name, start=value))
        for name, value in ode.parameters.items()
    ]
    u = [
        dae.add(name, "input", attrs(name, start=float(start)))
        for name, start in zip(ode.inputs, ode.input_start, strict=True)
    ]
    x = [
        dae.add(name, attrs(name, start=float(start)))
        for name, start in zip(ode.states, ode.state_start, strict=True)
    ]
    xdot, y = ode.ode(ca.vertcat(*x), ca.vertcat(*u), ca.vertcat(*p))
    for i, state in enumerate(x):
        dae.eq(dae.der(state), xdot[i])
    for i, name in enumerate(ode.outputs):
        dae.eq(dae.add(name, "output", attrs(name)), y[i])
    return dae


def _format_number(value: float) -> str:
    return repr(float(value))


def _unit_definitions(units_used: set[str]) -> ET.Element:
    element = ET.Element("UnitDefinitions")
    missing = sorted(units_used - set(UNIT_DEFINITIONS))
    if missing:
        raise SpindlebenchError(
            f"unit(s) {', '.join(missing)} used in the Modelica model have no SI definition in "
            "spindlebench.model.fmu_export.UNIT_DEFINITIONS"
        )
    for unit in sorted(units_used):
        unit_element = ET.SubElement(element, "Unit", name=unit)
        exponents = UNIT_DEFINITIONS[unit]
        base = {
            key: _format_number(v) if key in ("factor", "offset") else str(int(v))
            for key, v in exponents.items()
        }
        ET.SubElement(unit_element, "BaseUnit", {k: base[k] for k in BASE_UNIT_ORDER if k in base})
    return element


def fix_model_description(xml_text: str, ode: ExplicitOde, token: str) -> str:
    """Apply the modelDescription.xml repairs listed in the module docstring."""
    root = ET.fromstring(xml_text)
    root.attrib.pop("generationDateAndTime", None)
    root.set("instantiationToken", token)
    root.set("generationTool", _generation_tool())
    root.set(
        "description",
        f"Thermal network of a vertical machining centre, {ode.segments} segments per large part",
    )
    variables = root.find("ModelVariables")
    structure = root.find("ModelStructure")
    if variables is None or structure is None:
        raise SpindlebenchError("CasADi wrote a modelDescription.xml without variables")
    for variable in list(variables):
        if variable.get("name", "").startswith("__assign__"):
            variables.remove(variable)
    by_vr = {v.get("valueReference"): v for v in variables}
    starts = dict(zip(ode.states, ode.state_start, strict=True))
    derivative_vrs = []
    for variable in variables:
        state_vr = variable.get("derivative")
        if state_vr is None:
            continue
        derivative_vrs.append(variable.get("valueReference"))
        state = by_vr[state_vr]
        state.set("initial", "exact")
        state.set("start", _format_number(starts[state.get("name")]))
        variable.set("description", f"Time derivative of {state.get('name')}")
        if state.get("unit") == "K":
            variable.set("unit", "K/s")
    output_vrs = [v.get("valueReference") for v in variables if v.get("causality") == "output"]
    for unknown in structure.findall("InitialUnknown"):
        structure.remove(unknown)
    for vr in output_vrs + derivative_vrs:
        ET.SubElement(structure, "InitialUnknown", valueReference=vr)

    units_used = {v.get("unit") for v in variables if v.get("unit")}
    position = list(root).index(variables)
    root.insert(position, _unit_definitions(units_used))
    experiment = ET.Element(
        "DefaultExperiment",
        startTime="0.0",
        stopTime=_format_number(DEFAULT_STOP_TIME_S),
        tolerance="1e-06",
        stepSize="1.0",
    )
    root.insert(position + 1, experiment)
    _declare_interfaces(root)
    ET.indent(root, space="    ")
    return '<?xml version="1.0" encoding="UTF-8"?>\n' + ET.tostring(root, encoding="unicode") + "\n"


#: Capability flags both interfaces get from ``fmu_extensions.c`` (saved states).
STATE_FLAGS = {"canGetAndSetFMUState": "true", "canSerializeFMUState": "true"}


def _declare_interfaces(root: ET.Element) -> None:
    """Saved-state flags on ``<ModelExchange>``, and a ``<CoSimulation>`` element beside it
    (same binary, same model identifier: ``fmi3DoStep`` integrates the same functions)."""
    me = root.find("ModelExchange")
    if me is None or root.find("CoSimulation") is not None:
        raise SpindlebenchError("CasADi wrote a modelDescription.xml without a lone "
                                "<ModelExchange> element")
    me.attrib.update(STATE_FLAGS)
    cs = ET.Element("CoSimulation", {
        "modelIdentifier": me.get("modelIdentifier", FMU_NAME),
        **{k: me.get(k) for k in ("providesDirectionalDerivatives", "providesAdjointDerivatives")
           if me.get(k)},
        **STATE_FLAGS,
        "canHandleVariableCommunicationStepSize": "true",
        "hasEventMode": "false",
    })
    root.insert(list(root).index(me) + 1, cs)


def _generation_tool() -> str:
    versions = []
    for package in ("spindlebench", "pymoca", "casadi"):
        try:
            versions.append(f"{package} {metadata.version(package)}")
        except metadata.PackageNotFoundError:
            versions.append(package)
    return ", ".join(versions)


NO_EVENTS_FATAL = "  // No zero crossings\n  return fmi3Fatal;"
NO_EVENTS_OK = (
    "  // No zero crossings: nothing to report (patched by spindlebench)\n  return fmi3OK;"
)


START_PARAMETER = "T_start"
PATCH_NOTE = "(patched by spindlebench)"


def _replace_once(source: str, old: str, new: str, where: str) -> str:
    if source.count(old) != 1:
        raise SpindlebenchError(
            f"CasADi's FMU wrapper changed: the {where} patch no longer applies"
        )
    return source.replace(old, new)


def _replace_in_function(source: str, function: str, old: str, new: str) -> str:
    """Replace ``old`` once inside the body of the exported C function ``function``."""
    start = source.find(f"FMI3_Export fmi3Status {function}(")
    end = source.find("\nFMI3_Export", start + 1)
    if start < 0 or end < 0:
        raise SpindlebenchError(f"CasADi's FMU wrapper changed: {function} not found")
    body = _replace_once(source[start:end], old, new, function)
    return source[:start] + body + source[end:]


def patch_start_temperature(source: str, start_vr: int) -> str:
    """States not set by the importer start at the parameter with value reference ``start_vr``.

    The wrapper gets a per-instance flag per state: cleared by ``fmi3Reset``, set by
    ``fmi3SetFloat64``; ``fmi3EnterInitializationMode`` copies ``T_start`` into every state
    whose flag is still clear. A runner that sets all states by name is unaffected.
    """
    source = _replace_once(
        source,
        "  int continuous_states_changed;\n",
        "  int continuous_states_changed;\n"
        f"  // Which states the importer set before initialisation {PATCH_NOTE}\n"
        "  int state_set[N_X];\n",
        "state flags",
    )
    source = _replace_in_function(
        source,
        "fmi3Reset",
        "  m->continuous_states_changed = 0;\n",
        "  m->continuous_states_changed = 0;\n"
        "  for (i = 0; i < N_X; ++i) m->state_set[i] = 0;\n",
    )
    source = _replace_in_function(
        source,
        "fmi3SetFloat64",
        "    vr = valueReferences[i];\n",
        "    vr = valueReferences[i];\n"
        "    for (j = 0; j < N_X; ++j) if (x_vr[j] == vr) m->state_set[j] = 1;\n",
    )
    source = _replace_in_function(
        source,
        "fmi3EnterInitializationMode",
        "  casadi_fmi_memory* m;\n",
        "  casadi_fmi_memory* m;\n  size_t i;\n",
    )
    return _replace_in_function(
        source,
        "fmi3EnterInitializationMode",
        "  m->t = startTime;\n",
        "  m->t = startTime;\n"
        f"  // States the importer did not set start at {START_PARAMETER} {PATCH_NOTE}\n"
        "  for (i = 0; i < N_X; ++i)\n"
        f"    if (!m->state_set[i]) m->v[var_offset[x_vr[i]]] = m->v[var_offset[{start_vr}]];\n"
        "  m->up_to_date = 0;\n",
    )


#: The C code ``patch_extensions`` splices in; the marker splits its types from its functions.
EXTENSIONS_SOURCE = Path(__file__).with_name("fmu_extensions.c")
EXTENSIONS_SPLIT = "/* SB_SPLIT */\n"
#: Replaced by the instantiation token once the sources' digest is known (``export_fmu``).
TOKEN_PLACEHOLDER = "@SB_TOKEN@"
#: Exported functions CasADi leaves unimplemented, and the bodies ``fmu_extensions.c`` gives them.
EXTENSION_BODIES = {
    "fmi3Instance fmi3InstantiateCoSimulation": """  casadi_fmi_memory* m;
  (void)eventModeUsed;  // no event mode (hasEventMode = false)
  (void)earlyReturnAllowed;  // fmi3DoStep never returns early
  (void)requiredIntermediateVariables;
  (void)nRequiredIntermediateVariables;
  (void)intermediateUpdate;
  m = (casadi_fmi_memory*)fmi3InstantiateModelExchange(instanceName, instantiationToken,
      resourcePath, visible, loggingOn, instanceEnvironment, logMessage);
  if (m) m->sb_is_cs = 1;
  return m;
""",
    "fmi3Status fmi3GetFMUState": "  return sb_get_state((casadi_fmi_memory*)instance, "
                                  "FMUState);\n",
    "fmi3Status fmi3SetFMUState": "  return sb_set_state((casadi_fmi_memory*)instance, "
                                  "FMUState);\n",
    "fmi3Status fmi3FreeFMUState": "  (void)instance;\n  return sb_free_state(FMUState);\n",
    "fmi3Status fmi3SerializedFMUStateSize": """  (void)instance;
  (void)FMUState;
  *size = sizeof(sb_fmu_state);
  return fmi3OK;
""",
    "fmi3Status fmi3SerializeFMUState": "  return sb_serialize((casadi_fmi_memory*)instance, "
                                        "FMUState, serializedState, size);\n",
    "fmi3Status fmi3DeserializeFMUState": "  return sb_deserialize((casadi_fmi_memory*)instance, "
                                          "serializedState, size, FMUState);\n",
    "fmi3Status fmi3EnterStepMode": "  (void)instance;\n  return fmi3OK;\n",
    "fmi3Status fmi3DoStep": """  fmi3Status status;
  casadi_fmi_memory* m = (casadi_fmi_memory*)instance;
  (void)noSetFMUStatePriorToCurrentPoint;
  status = sb_do_step(m, currentCommunicationPoint, communicationStepSize);
  if (eventHandlingNeeded) *eventHandlingNeeded = fmi3False;
  if (terminateSimulation) *terminateSimulation = fmi3False;
  if (earlyReturn) *earlyReturn = fmi3False;
  if (lastSuccessfulTime) *lastSuccessfulTime = m->t;
  return status;
""",
}


#: Replaced by ``jacobian_structure`` (C tables) in the extensions' CVode Jacobian.
JACOBIAN_PLACEHOLDER = "@SB_JACOBIAN_STRUCTURE@"


def jacobian_structure(xml_text: str) -> str:
    """C tables of d xdot / d x's structure and a colouring of its columns, from the model
    description's ``<ContinuousStateDerivative dependencies>`` (CasADi's sparsity, checked
    by ``build --cross-check``): per state (in the order of the derivatives, which is the
    wrapper's ``x_vr``, checked in C through ``sb_jac_state_vr``) its colour and the rows
    (derivatives) it reaches. Greedy colouring in column order: a column takes the first
    colour none of whose columns shares a row with it, so one forward derivative per colour
    gives every column of that colour."""
    root = ET.fromstring(xml_text)
    structure, variables = root.find("ModelStructure"), root.find("ModelVariables")
    if structure is None or variables is None:
        raise SpindlebenchError("CasADi wrote a modelDescription.xml without a model structure")
    by_vr = {v.get("valueReference"): v for v in variables}
    derivatives = structure.findall("ContinuousStateDerivative")
    state_vrs = [int(by_vr[d.get("valueReference")].get("derivative")) for d in derivatives]
    column = {vr: j for j, vr in enumerate(state_vrs)}
    rows: list[list[int]] = [[] for _ in state_vrs]
    for i, derivative in enumerate(derivatives):
        listed = derivative.get("dependencies")
        depends = (state_vrs if listed is None  # omitted: depends on everything
                   else [int(vr) for vr in listed.split() if int(vr) in column])
        for vr in depends:
            rows[column[vr]].append(i)
    colours: list[int] = []
    used: list[set[int]] = []  # rows reached per colour
    for reached in rows:
        colour = next((c for c, taken in enumerate(used) if taken.isdisjoint(reached)),
                      len(used))
        if colour == len(used):
            used.append(set())
        used[colour].update(reached)
        colours.append(colour)
    starts = [0]
    for reached in rows:
        starts.append(starts[-1] + len(reached))

    def table(kind: str, name: str, values: list[int]) -> str:
        return (f"static const {kind} {name}[{max(1, len(values))}] = "
                f"{{{', '.join(map(str, values or [0]))}}};")

    return "\n".join([
        f"#define SB_JAC_COLORS {len(used)}",
        table("fmi3ValueReference", "sb_jac_state_vr", state_vrs),
        table("int", "sb_jac_color", colours),
        table("size_t", "sb_jac_colstart", starts),
        table("size_t", "sb_jac_row", [i for reached in rows for i in reached]),
    ])


def _replace_body(source: str, signature: str, body: str) -> str:
    """Replace the body of the exported C function that starts with ``signature``."""
    start = source.find(f"FMI3_Export {signature}(")
    brace = source.find(") {\n", start)
    end = source.find("\nFMI3_Export", start + 1)
    if start < 0 or brace < 0 or end < 0 or not start < brace < end:
        raise SpindlebenchError(f"CasADi's FMU wrapper changed: {signature} not found")
    return source[:brace + 4] + body + "}" + source[end:]


def patch_extensions(source: str) -> str:
    """Splice ``fmu_extensions.c`` into the wrapper (co-simulation, saved states, the
    value-reference table) and route the unimplemented FMI functions to it."""
    types, functions = EXTENSIONS_SOURCE.read_text(encoding="utf-8").split(EXTENSIONS_SPLIT)
    source = _replace_once(source, "typedef struct {\n  // Name of instance\n",
                           f"{types}\ntypedef struct {{\n  // Name of instance\n",
                           "extension types")
    source = _replace_once(
        source,
        "  int state_set[N_X];\n",
        "  int state_set[N_X];\n"
        f"  // spindlebench extensions {PATCH_NOTE}: value reference -> state index (-1: none),\n"
        "  // co-simulation integrator memory and work arrays, the importer's logger, what the\n"
        "  // CVode callbacks in C need from the importer\n"
        "  int sb_state_of_vr[N_VAR];\n  int sb_is_cs;\n  sb_integrator sb_cs;\n"
        "  sb_work* sb_work;\n  fmi3LogMessageCallback sb_log;\n"
        "  fmi3InstanceEnvironment sb_env;\n  sb_host* sb_host;\n",
        "extension memory",
    )
    source = _replace_once(
        source, "FMI3_Export fmi3Status fmi3Reset(",
        f'#define SB_TOKEN "{TOKEN_PLACEHOLDER}"\n{functions}\nFMI3_Export fmi3Status fmi3Reset(',
        "extension functions")
    source = _replace_in_function(
        source, "fmi3Reset", "  m->continuous_states_changed = 0;\n",
        "  m->continuous_states_changed = 0;\n"
        "  m->sb_cs.h = 0;\n  m->sb_cs.jac_valid = 0;\n  m->sb_cs.lu_hg = 0;\n")
    source = _replace_once(
        source, "    m->instance_name = instanceName;\n",
        "    m->instance_name = instanceName;\n    sb_init_extensions(m);\n"
        "    m->sb_log = logMessage;\n    m->sb_env = instanceEnvironment;\n",
        "instantiation")
    source = _replace_once(source, "    // Free memory structure\n    free(instance);\n",
                           "    // Free memory structure\n"
                           "    free(((casadi_fmi_memory*)instance)->sb_work);\n"
                           "    if (((casadi_fmi_memory*)instance)->sb_host)\n"
                           "      free(((casadi_fmi_memory*)instance)->sb_host->table);\n"
                           "    free(((casadi_fmi_memory*)instance)->sb_host);\n"
                           "    free(instance);\n", "fmi3FreeInstance")
    source = _replace_in_function(
        source, "fmi3EnterInitializationMode", "  m->t = startTime;\n",
        "  m->t = startTime;\n"
        "  if (toleranceDefined && tolerance > 0) m->sb_cs.tol = tolerance;\n")
    source = _replace_in_function(
        source, "fmi3SetFloat64",
        "    for (j = 0; j < N_X; ++j) if (x_vr[j] == vr) m->state_set[j] = 1;\n",
        "    if (vr < N_VAR && m->sb_state_of_vr[vr] >= 0) "
        "m->state_set[m->sb_state_of_vr[vr]] = 1;\n")
    for signature, body in EXTENSION_BODIES.items():
        source = _replace_body(source, signature, body)
    return source


def patch_wrapper(source: str, start_vr: int | None = None) -> str:
    """Make ``fmi3GetEventIndicators`` succeed for a model without event indicators, (with
    ``start_vr``) start unset states at ``T_start``, and add ``fmu_extensions.c``."""
    source = _replace_once(source, NO_EVENTS_FATAL, NO_EVENTS_OK, "fmi3GetEventIndicators")
    if start_vr is None:  # the extensions' saved states include the state flags it adds
        raise SpindlebenchError(f"the model has no parameter {START_PARAMETER!r}, which the "
                                "FMU's start-temperature patch needs")
    return patch_extensions(patch_start_temperature(source, start_vr))


def _value_reference(xml_text: str, name: str) -> int | None:
    for variable in ET.fromstring(xml_text).iter():
        if variable.get("name") == name and variable.get("valueReference") is not None:
            return int(variable.get("valueReference"))
    return None


def compile_binary(sources: list[Path], include_dir: Path, output: Path) -> None:
    """Compile the model and wrapper C sources into the FMU's shared library."""
    import fmpy

    compiler = find_compiler()
    headers = Path(fmpy.__file__).parent / "c-code"
    command = [
        *compiler,
        "-shared",
        "-fPIC",
        "-O2",
        "-std=c99",
        f"-I{headers}",
        f"-I{include_dir}",
        *[str(s) for s in sources],
        "-o",
        str(output),
        "-lm",
    ]
    output.parent.mkdir(parents=True, exist_ok=True)
    result = subprocess.run(command, capture_output=True, text=True, check=False)
    if result.returncode != 0:
        first = (result.stderr.strip().splitlines() or ["(no message)"])[0]
        raise SpindlebenchError(f"compiling the FMU binary failed ({compiler[0]}): {first}")


def write_zip(folder: Path, target: Path) -> None:
    """Zip ``folder`` reproducibly (sorted entries, fixed dates and permissions), atomically."""
    files = sorted(p for p in folder.rglob("*") if p.is_file())
    with atomic.atomic_path(target) as tmp, zipfile.ZipFile(tmp, "w") as archive:
        for path in files:
            info = zipfile.ZipInfo(path.relative_to(folder).as_posix(), date_time=ZIP_DATE)
            info.compress_type = zipfile.ZIP_DEFLATED
            info.create_system = 3
            info.external_attr = 0o644 << 16
            archive.writestr(info, path.read_bytes(), compresslevel=9)
        tmp.chmod(0o644)


def export_fmu(ode: ExplicitOde, out_path: str | Path) -> Path:
    """Write the FMU for ``ode`` to ``out_path`` (atomically) and return the path."""
    out_path = Path(out_path)
    find_compiler()  # fail before the slow part
    folder, suffix = platform_tuple()
    dae = _dae_builder(ode)
    with tempfile.TemporaryDirectory(prefix="spindlebench-fmu-") as tmp_name:
        staging = Path(tmp_name)
        previous = Path.cwd()
        os.chdir(staging)  # DaeBuilder.export_fmu writes into the working directory
        try:
            files = dae.export_fmu({"no_warning": True, "with_serialization": False})
        finally:
            os.chdir(previous)
        package = staging / "fmu"
        for local, inside in files.items():
            destination = package / inside
            destination.parent.mkdir(parents=True, exist_ok=True)
            shutil.move(str(staging / local), destination)
        sources_dir = package / "sources"
        wrapper = sources_dir / f"{FMU_NAME}_wrap.c"
        description = package / "modelDescription.xml"
        start_vr = (
            _value_reference(description.read_text(), START_PARAMETER)
            if START_PARAMETER in ode.parameters
            else None
        )
        wrapper.write_text(patch_wrapper(wrapper.read_text(), start_vr).replace(
            JACOBIAN_PLACEHOLDER, jacobian_structure(description.read_text())))
        c_sources = sorted(sources_dir.glob("*.c"))
        digest = hashlib.sha256()
        for source in c_sources:
            digest.update(source.read_bytes())
        token = "{" + digest.hexdigest()[:32] + "}"
        wrapper.write_text(wrapper.read_text().replace(TOKEN_PLACEHOLDER, token))
        description.write_text(fix_model_description(description.read_text(), ode, token))
        compile_binary(
            c_sources, sources_dir, package / "binaries" / folder / f"{FMU_NAME}{suffix}"
        )
        write_zip(package, out_path)
    return out_path
