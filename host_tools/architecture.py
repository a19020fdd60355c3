"""The project's structure, read from its code: the import graph of the Python packages, the call graph of the C
core's files, the circles in either (there must be none: each layer calls only the layers below it), and the
picture of the three halves and a frame's way to a setpoint in docs/DESIGN.md, which ``make docs`` draws from
``DATA_FLOW`` (every step names the function that does it; a renamed or moved function fails the drawing) and
from the imports between the rooms of each half.
"""
import ast
import re
from dataclasses import dataclass
from pathlib import Path

REPO_ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("crazyflie_app", "host_tools", "jevois_module")
C_CORE = REPO_ROOT / "crazyflie_app" / "bolt" / "src"
# the rooms of each half: the picture lists which of them imports which
ROOMS = ("jevois_module.ForaNavTrees", "crazyflie_app.app", "crazyflie_app.bolt", "crazyflie_app.firmware",
         "host_tools.sim", "host_tools.detection", "host_tools.flight", "host_tools.sweep", "host_tools.jevois_host",
         "host_tools.deploy")
_C_DEFINITION = re.compile(r"^[A-Za-z][\w \*]*?\b(\w+)\s*\([^;{]*\)\s*\{", re.M)
_C_CALL = re.compile(r"\b(\w+)\s*\(")


@dataclass(frozen=True)
class Step:
    """One step of a frame's way: where it runs, what happens, and the function that does it
    (``path/to/file.py:Class.method``, or a C function in ``crazyflie_app/bolt/src``)."""
    where: str
    what: str
    done_by: str


DATA_FLOW = (
    Step("host", "render the frame the camera sees from the true pose (352x288 BGR)",
         "host_tools/flight/vision_camera.py:VisionCamera.render"),
    Step("camera", "the module's frame callback", "jevois_module/ForaNavTrees/ForaNavTrees.py:ForaNavTrees.processNoUSB"),
    Step("camera", "HOG + SVM score maps, grouping, colour and texture cues -> crowns",
         "jevois_module/ForaNavTrees/foranav_detector.py:TreeDetector.detect"),
    Step("camera", "one \"T2 x y\" line per crown, then \"MARK STOP\"",
         "jevois_module/ForaNavTrees/foranav_serial.py:format_t2"),
    Step("wire", "the camera's UART at 115200 8N1 (host: a real pty)", "host_tools/flight/wire.py:PtyWire.write"),
    Step("flight controller", "UART2 and its 200-byte receive buffer", "crazyflie_app/firmware/uart2.py:Uart2.rx_task"),
    Step("flight controller", "the app's camera task: lines -> one frame per MARK STOP",
         "crazyflie_app/app/navigation.py:NavigationApp.camera_task"),
    Step("flight controller", "detections -> ground, tree memory, column rule, target, pixel Kalman filter",
         "crazyflie_app/app/navigation_core.py:NavigationCore.on_frame"),
    Step("flight controller", "the state machine every 10 ms -> hover setpoint (vx, vy, z)",
         "crazyflie_app/app/navigation_core.py:NavigationCore.step"),
    Step("flight controller", "the same core in C (the Bolt's bolt.bin, and --app c)", "navCoreStep"),
    Step("flight controller", "commanderSetSetpoint at COMMANDER_PRIORITY_EXTRX",
         "crazyflie_app/firmware/commander.py:Commander.commander_set_setpoint"),
    Step("plant reduced", "supervisor, reduced MAV model at 100 Hz",
         "crazyflie_app/firmware/reduced/stack.py:ReducedFlightStack.stabilizer_task"),
    Step("plant firmware", "the firmware's PID controller, Kalman estimator, supervisor over a rigid body at 1 kHz",
         "crazyflie_app/firmware/sil/plant.py:FirmwareFlightStack.stabilizer_task"),
    Step("host", "the new true pose -> the next frame", "host_tools/flight/components.py:CameraFeed.task"),
)


def _module_name(path: Path) -> str:
    parts = path.relative_to(REPO_ROOT).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def python_imports() -> dict[str, set[str]]:
    """Module -> the project's modules it imports, wherever the import stands (in a function, under
    TYPE_CHECKING: hiding an import does not break a circle). ``from package import module`` names the module."""
    paths = {_module_name(path): path for package in PACKAGES for path in (REPO_ROOT / package).rglob("*.py")}
    graph = {}
    for name, path in paths.items():
        imported = set()
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Import):
                imported.update(alias.name for alias in node.names)
            elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
                imported.update(node.module + "." + alias.name if node.module + "." + alias.name in paths
                                else node.module for alias in node.names)
        graph[name] = {target for target in imported if target in paths and target != name}
    return graph


def _without_c_comments(text: str) -> str:
    return re.sub(r"//[^\n]*", "", re.sub(r"/\*.*?\*/", "", text, flags=re.S))


def _c_texts(source_dir: Path) -> dict[str, str]:
    return {path.name: _without_c_comments(path.read_text(encoding="utf-8")) for path in sorted(source_dir.glob("*.c"))}


def c_definitions(source_dir: Path = C_CORE) -> dict[str, str]:
    """C function name -> the file of ``source_dir`` that defines it."""
    return {match.group(1): name for name, text in _c_texts(source_dir).items()
            for match in _C_DEFINITION.finditer(text)}


def c_calls(source_dir: Path = C_CORE) -> dict[str, set[str]]:
    """C file -> the other files of ``source_dir`` whose functions it calls."""
    defined_in = c_definitions(source_dir)
    return {name: {defined_in[call.group(1)] for call in _C_CALL.finditer(text)
                   if defined_in.get(call.group(1), name) != name}
            for name, text in _c_texts(source_dir).items()}


def circles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one node (Tarjan), each sorted."""
    order, low, stack, on_stack, found = {}, {}, [], set(), []

    def visit(node):
        order[node] = low[node] = len(order)
        stack.append(node)
        on_stack.add(node)
        for target in sorted(graph[node]):
            if target not in order:
                visit(target)
                low[node] = min(low[node], low[target])
            elif target in on_stack:
                low[node] = min(low[node], order[target])
        if low[node] == order[node]:
            component = []
            while not component or component[-1] != node:
                component.append(stack.pop())
                on_stack.discard(component[-1])
            if len(component) > 1:
                found.append(sorted(component))

    for node in sorted(graph):
        if node not in order:
            visit(node)
    return found


def _room(module: str) -> str | None:
    return next((room for room in ROOMS if module == room or module.startswith(room + ".")), None)


def room_imports(graph: dict[str, set[str]] | None = None) -> dict[str, list[str]]:
    """Room -> the other rooms its modules import, from the import graph."""
    graph = python_imports() if graph is None else graph
    edges = {room: set() for room in ROOMS}
    for module, targets in graph.items():
        source = _room(module)
        for target in targets:
            target_room = _room(target)
            if source and target_room and target_room != source:
                edges[source].add(target_room)
    return {room: sorted(targets) for room, targets in edges.items()}


def _python_definition_exists(path: Path, qualname: str) -> bool:
    scope = ast.parse(path.read_text(encoding="utf-8")).body
    for part in qualname.split("."):
        found = next((node for node in scope if isinstance(node, (ast.FunctionDef, ast.ClassDef))
                      and node.name == part), None)
        if found is None:
            return False
        scope = found.body
    return True


def missing_steps(flow: tuple[Step, ...] = DATA_FLOW) -> list[str]:
    """The ``done_by`` of every step whose function is not where the step says."""
    c_functions = c_definitions()
    missing = []
    for step in flow:
        if ":" in step.done_by:
            file_name, qualname = step.done_by.split(":")
            path = REPO_ROOT / file_name
            if not path.is_file() or not _python_definition_exists(path, qualname):
                missing.append(step.done_by)
        elif step.done_by not in c_functions:
            missing.append(step.done_by)
    return missing


def picture() -> str:
    """DESIGN.md's picture: a frame's way round the loop, then which room of each half imports which."""
    missing = missing_steps()
    if missing:
        raise ValueError("architecture.DATA_FLOW names functions that are not there: %s" % ", ".join(missing))
    width = max(len(step.where) for step in DATA_FLOW)
    lines = ["a frame's way round the loop (where | what | done by):", ""]
    lines += ["  %s | %s" % (step.where.ljust(width), step.what) + "\n  %s |   %s" % (" " * width, step.done_by)
              for step in DATA_FLOW]
    lines += ["", "who imports whom (rooms of the three halves; host_tools drives the other two):", ""]
    lines += ["  %s -> %s" % (room, ", ".join(targets) if targets else "(nothing of ours)")
              for room, targets in room_imports().items()]
    return "\n".join(lines)
