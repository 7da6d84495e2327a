"""The rules of docs/architecture.md that can be read off the source: checked by static analysis (``ast``).

* Data flows one way: the problem-data layer (``contactqvi/problems/``, ``case.py``,
  ``load_steps.py``, ``obstacles.py``, ``interference.py``, the contact laws ``contactqvi/laws/``) imports no solver
  package (``contact``, ``friction``, ``vi``, ``qvi``).
* No import cycle in the package (imports at module level, in functions and under
  ``TYPE_CHECKING`` alike; ``from package import module`` counts as an import of the module).
* One lifetime rule: every class that keeps PETSc objects it creates, or has a
  ``destroy()``, derives from :class:`contactqvi.lifetime.PETScOwner`.
* No function longer than 60 lines.
* A test marked ``one_rank`` (left out of the runs on several ranks) reaches no code that runs
  differently in parallel (:data:`PARALLEL_NAMES`), through its helpers, fixtures and values.

Nothing is imported or run: the tests read the files.
"""

from __future__ import annotations

import ast
import dataclasses
import pathlib

import pytest

pytestmark = pytest.mark.one_rank(reason="the source files read and checked statically: the same on every rank")

PACKAGE = pathlib.Path(__file__).resolve().parent.parent / "contactqvi"
SOLVER_PACKAGES = ("contactqvi.contact", "contactqvi.friction", "contactqvi.vi", "contactqvi.qvi")
DATA_LAYER = ("contactqvi.problems", "contactqvi.case", "contactqvi.load_steps", "contactqvi.obstacles",
              "contactqvi.laws", "contactqvi.interference")
MAX_FUNCTION_LINES = 60
#: Calls that create a PETSc object: petsc4py's camel-case constructors and copies, and the factories.
CREATING_METHODS = ("duplicate", "getDiagonal", "convert", "createVecs")
CREATING_FUNCTIONS = ("create_ksp", "create_snes", "create_vector", "create_matrix", "diagonal_matrix",
                      "rigid_motions_nullspace")  # fmt: skip
#: Classes outside the rule, and why.
LIFETIME_EXCEPTIONS = {
    "EmbeddedInactivePC": "a petsc4py Python-PC context: PETSc calls its destroy(pc) with the PC",
}


@dataclasses.dataclass
class Module:
    name: str
    path: pathlib.Path
    tree: ast.Module


def _modules() -> dict[str, Module]:
    modules = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
        name = ".".join(parts[:-1] if parts[-1] == "__init__" else parts)
        modules[name] = Module(name, path, ast.parse(path.read_text(), str(path)))
    return modules


MODULES = _modules()


def _imports(module: Module) -> set[str]:
    """The package's modules that ``module`` imports, anywhere in its source."""
    is_package = module.path.name == "__init__.py"
    found = set()
    for node in ast.walk(module.tree):
        if isinstance(node, ast.Import):
            found.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = module.name.split(".")[: len(module.name.split(".")) - node.level + is_package]
                base = ".".join([*anchor, *([base] if base else [])])
            for alias in node.names:
                found.add(f"{base}.{alias.name}" if f"{base}.{alias.name}" in MODULES else base)
    return {name for name in found if name in MODULES and name != module.name}


GRAPH = {name: _imports(module) for name, module in MODULES.items()}


def _inside(name: str, packages: tuple[str, ...]) -> bool:
    return any(name == p or name.startswith(p + ".") for p in packages)


@pytest.mark.parametrize("name", sorted(n for n in MODULES if _inside(n, DATA_LAYER)))
def test_problem_data_imports_no_solver(name):
    solvers = sorted(target for target in GRAPH[name] if _inside(target, SOLVER_PACKAGES))
    assert not solvers, f"{name} (problem data) imports the solver modules {solvers}"


def _cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components with more than one module (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    components = []

    def visit(node: str) -> None:
        index[node] = low[node] = len(index)
        stack.append(node)
        for target in sorted(graph[node]):
            if target not in index:
                visit(target)
                low[node] = min(low[node], low[target])
            elif target in stack:
                low[node] = min(low[node], index[target])
        if low[node] == index[node]:
            component = []
            while not component or component[-1] != node:
                component.append(stack.pop())
            if len(component) > 1:
                components.append(sorted(component))

    for node in sorted(graph):
        if node not in index:
            visit(node)
    return components


def test_the_cycle_finder_finds_a_cycle():
    assert _cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert _cycles({"a": {"b"}, "b": set()}) == []


def test_no_import_cycle():
    cycles = _cycles(GRAPH)
    details = [" <-> ".join(c) + ": " + "; ".join(f"{m} imports {sorted(GRAPH[m] & set(c))}" for m in c)
               for c in cycles]  # fmt: skip
    assert not cycles, "\n".join(details)


def _classes() -> dict[str, tuple[str, ast.ClassDef]]:
    return {node.name: (m.name, node) for m in MODULES.values() for node in ast.walk(m.tree)
            if isinstance(node, ast.ClassDef)}  # fmt: skip


CLASSES = _classes()


def _base_names(node: ast.ClassDef) -> list[str]:
    return [base.attr if isinstance(base, ast.Attribute) else getattr(base, "id", "") for base in node.bases]


def _is_owner(name: str) -> bool:
    if name == "PETScOwner":
        return True
    return name in CLASSES and any(_is_owner(base) for base in _base_names(CLASSES[name][1]))


def _petsc_assemblers(module: Module) -> set[str]:
    """Names bound to dolfinx.fem.petsc's assemble_matrix/assemble_vector by ``from ... import``."""
    return {alias.asname or alias.name for node in ast.walk(module.tree) if isinstance(node, ast.ImportFrom)
            and node.module == "dolfinx.fem.petsc" for alias in node.names}  # fmt: skip


def _creates_petsc_object(node: ast.AST, assemblers: set[str] = frozenset()) -> bool:
    for call in (n for n in ast.walk(node) if isinstance(n, ast.Call)):
        func = call.func
        name = func.attr if isinstance(func, ast.Attribute) else getattr(func, "id", "")
        if name in CREATING_METHODS + CREATING_FUNCTIONS or (name.startswith("create") and name[6:7].isupper()):
            return True
        petsc = name in assemblers if isinstance(func, ast.Name) else "petsc" in ast.unparse(func.value)
        if name in ("assemble_matrix", "assemble_vector") and petsc and len(call.args) == 1:  # not in place
            return True
    return False


def _keeps_petsc_objects(node: ast.ClassDef, assemblers: set[str] = frozenset()) -> bool:
    """Whether a method assigns a newly created PETSc object to an attribute of ``self``."""
    for assign in (n for n in ast.walk(node) if isinstance(n, (ast.Assign, ast.AnnAssign))):
        targets = assign.targets if isinstance(assign, ast.Assign) else [assign.target]
        on_self = [t for target in targets for t in ast.walk(target)
                   if isinstance(t, ast.Attribute) and getattr(t.value, "id", "") == "self"]  # fmt: skip
        if on_self and assign.value is not None and _creates_petsc_object(assign.value, assemblers):
            return True
    return False


def _defines(node: ast.ClassDef, method: str) -> bool:
    return any(isinstance(n, ast.FunctionDef) and n.name == method for n in node.body)


def _names_its_objects(name: str) -> bool:
    """Whether the class or a base below PETScOwner defines ``petsc_objects``."""
    if name not in CLASSES or name == "PETScOwner":
        return False
    node = CLASSES[name][1]
    return _defines(node, "petsc_objects") or any(_names_its_objects(base) for base in _base_names(node))


def test_the_lifetime_check_sees_an_owner():
    owner = ast.parse("class A:\n    def __init__(self, x):\n        self.v = x.createVecLeft()\n").body[0]
    scratch = ast.parse("class B:\n    def f(self, x):\n        v = x.duplicate()\n        v.destroy()\n").body[0]
    assembled = ast.parse("class C:\n    def f(self, a):\n        self.A = dolfinx.fem.petsc.assemble_matrix(a)\n")
    not_petsc = ast.parse("class D:\n    def f(self, a):\n        self.b = fem.assemble_vector(a).array\n")
    assert _keeps_petsc_objects(owner) and not _keeps_petsc_objects(scratch)
    assert _keeps_petsc_objects(assembled.body[0]) and not _keeps_petsc_objects(not_petsc.body[0])


@pytest.mark.parametrize("name", sorted(CLASSES))
def test_every_owner_of_petsc_objects_follows_the_lifetime_rule(name):
    module, node = CLASSES[name]
    keeps = _keeps_petsc_objects(node, _petsc_assemblers(MODULES[module]))
    if name in LIFETIME_EXCEPTIONS or not (keeps or _defines(node, "destroy")):
        return
    assert _is_owner(name), (f"{module}.{name} keeps PETSc objects or has a destroy() but does not derive from "
                             "contactqvi.lifetime.PETScOwner (petsc_objects(), destroy(), with)")  # fmt: skip
    assert not keeps or _names_its_objects(name), f"{module}.{name} keeps PETSc objects but has no petsc_objects()"


def _long_functions(module: Module) -> list[str]:
    return [f"{node.name} (line {node.lineno}): {node.end_lineno - node.lineno + 1} lines"
            for node in ast.walk(module.tree) if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef))
            and node.end_lineno - node.lineno + 1 > MAX_FUNCTION_LINES]  # fmt: skip


@pytest.mark.parametrize("name", sorted(MODULES))
def test_no_function_is_longer_than_60_lines(name):
    long = _long_functions(MODULES[name])
    assert not long, f"{name}: {', '.join(long)}"


# --- The split of the suite between its runs (tests/conftest.py) ---------------------------------

TESTS = PACKAGE.parent / "tests"
#: Names by which a test reaches code that runs differently on several ranks, and what differs.
#: A test marked ``one_rank`` runs on one rank only, so it must reach none of them: not in its
#: body, its decorators (parametrize), the fixtures it asks for, nor in the functions, fixtures
#: and module-level values of its module, of conftest.py and of the test helpers it uses
#: (followed to any depth). The library is not followed: its functions take a communicator,
#: except those listed here that default to ``MPI.COMM_WORLD``. A helper called on
#: ``MPI.COMM_SELF`` is serial arithmetic on every rank and allowed.
PARALLEL_NAMES = {
    "COMM_WORLD": "distributed meshes and vectors: ghosts, owned ranges, reductions, parallel assembly and solvers",
    "mpi_tmp_path": "one directory written by every rank",
    "load_demo": "the demos run on MPI.COMM_WORLD",
    "run_case": "the case runner (MPI.COMM_WORLD by default): searches, output, checkpoints, restart",
    "ContactResultsWriter": "ParaView output of the contact results (MPI.COMM_WORLD by default)",
    "abort_on_error": "an error on one rank of several aborts the job (MPI.COMM_WORLD by default)",
    "CheckpointWriter": "checkpoints written by every rank (adios4dolfinx)",
    "read_checkpoint": "checkpoints read back on any number of ranks",
    "BodyPair": "a body pair: its master surface searched across ranks",
    "mortar_coupling": "mortar search and integration, master facets exchanged between ranks",
    "search_again": "a contact search again in the deformed configuration, across ranks",
    "VTXDatasetWriter": "VTX datasets, each rank its own block",
    "write_vtx": "VTX output of Functions in parallel",
    "write_vtx_dataset": "VTX output in parallel",
    "write_xdmf": "XDMF output in parallel",
    "gather_pieces": "gathering the ranks' pieces of a dataset",
    "gather_vertex_values": "gathering a field on rank 0",
    "write_solution_npz": "solution.npz gathered on rank 0",
}
#: Modules of tests/ that tests import helpers from.
TEST_HELPERS = ("conftest", "law_checks", "friction_checks", "mortar_checks", "output_files", "petsc_audit",
                "program_runs", "shipped_runs")


def _test_namespace(tree: ast.Module, helpers: dict[str, ast.Module]) -> dict[str, ast.AST]:
    """What each name of a test module's top level stands for: a function, class or value
    defined there, a helper imported from tests/ (``from law_checks import f``: f's definition;
    ``import petsc_audit``: the whole module), or a fixture of conftest.py."""
    namespace: dict[str, ast.AST] = {}
    conftest = helpers.get("conftest")
    if conftest is not None and conftest is not tree:
        namespace.update({n.name: n for n in conftest.body if isinstance(n, ast.FunctionDef)})
    for node in tree.body:
        if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.ClassDef)):
            namespace[node.name] = node
        elif isinstance(node, (ast.Assign, ast.AnnAssign, ast.AugAssign)):
            targets = node.targets if isinstance(node, ast.Assign) else [node.target]
            namespace.update({n.id: node for t in targets for n in ast.walk(t) if isinstance(n, ast.Name)})
        elif isinstance(node, ast.ImportFrom) and node.module in helpers and not node.level:
            defined = {n.name: n for n in helpers[node.module].body if hasattr(n, "name")}
            namespace.update({a.asname or a.name: defined.get(a.name, helpers[node.module]) for a in node.names})
        elif isinstance(node, ast.Import):
            namespace.update({a.asname or a.name: helpers[a.name] for a in node.names if a.name in helpers})
    return namespace


def _used_names(node: ast.AST) -> set[str]:
    """Names, attributes and arguments (fixtures) appearing in ``node``."""
    found = set()
    for n in ast.walk(node):
        if isinstance(n, ast.Name):
            found.add(n.id)
        elif isinstance(n, ast.Attribute):
            found.add(n.attr)
        elif isinstance(n, ast.arg):
            found.add(n.arg)
    return found


def parallel_paths(source: str, helpers: dict[str, str] | None = None) -> dict[str, list[str]]:
    """For each test function of ``source``: how it reaches :data:`PARALLEL_NAMES`, as
    ``"helper -> fixture -> NAME"`` chains (empty: it stays serial arithmetic on every rank).

    ``helpers`` maps the module names of tests/ (:data:`TEST_HELPERS`) to their sources."""
    trees = {name: ast.parse(text) for name, text in (helpers or {}).items()}
    tree = ast.parse(source)
    namespaces = {id(t): _test_namespace(t, trees) for t in [tree, *trees.values()]}
    owner = {id(n): t for t in [tree, *trees.values()] for n in ast.walk(t)}

    def reach(node: ast.AST, seen: set[int], via: tuple[str, ...]) -> list[str]:
        namespace = namespaces[id(owner[id(node)])]
        chains = [" -> ".join([*via, name]) for name in sorted(_used_names(node)) if name in PARALLEL_NAMES]
        for name in sorted(_used_names(node)):
            target = namespace.get(name)
            if target is not None and target is not node and id(target) not in seen:
                seen.add(id(target))
                chains += reach(target, seen, (*via, name))
        return chains

    return {node.name: reach(node, {id(node)}, ()) for node in ast.walk(tree)
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)) and node.name.startswith("test")}  # fmt: skip


def _one_rank_tests(tree: ast.Module) -> set[str]:
    """Test functions marked ``one_rank``, on the function or on the whole module (``pytestmark``)."""

    def marked(nodes) -> bool:
        return any(isinstance(n, ast.Attribute) and n.attr == "one_rank" for d in nodes for n in ast.walk(d))

    module = [n.value for n in tree.body if isinstance(n, ast.Assign)
              and any(getattr(t, "id", "") == "pytestmark" for t in n.targets)]  # fmt: skip
    return {node.name for node in ast.walk(tree) if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef))
            and node.name.startswith("test") and (marked(module) or marked(node.decorator_list))}  # fmt: skip


TEST_MODULES = sorted(TESTS.glob("test_*.py"))
HELPER_SOURCES = {name: (TESTS / f"{name}.py").read_text() for name in TEST_HELPERS if (TESTS / f"{name}.py").exists()}


def test_the_split_checker_sees_parallel_code():
    """Planted examples: reached directly, through a module helper, a fixture, a parametrize
    argument, a module-level value and a test helper; COMM_SELF and plain numpy stay serial."""
    helpers = {"conftest": "import pytest\n@pytest.fixture\ndef world():\n    return MPI.COMM_WORLD\n",
               "law_checks": "def check(u):\n    return MPI.COMM_WORLD.allreduce(u)\n"}  # fmt: skip
    source = (
        "import pytest\nfrom law_checks import check\nMESH = create_mesh(MPI.COMM_WORLD)\n"
        "def _problem(comm):\n    return comm\n"
        "def _world():\n    return _problem(MPI.COMM_WORLD)\n"
        "@pytest.mark.one_rank(reason='planted')\ndef test_direct():\n    assert MPI.COMM_WORLD.size\n"
        "def test_helper():\n    _world()\n"
        "def test_fixture(world):\n    pass\n"
        "def test_shared_dir(mpi_tmp_path):\n    pass\n"
        "@pytest.mark.parametrize('comm', [MPI.COMM_WORLD])\ndef test_parametrized(comm):\n    pass\n"
        "def test_module_value():\n    assert MESH\n"
        "def test_test_helper():\n    check(1)\n"
        "def test_runner(tmp_path):\n    run_case(case, tmp_path)\n"
        "def test_serial(tmp_path):\n    _problem(MPI.COMM_SELF)\n    np.linalg.norm([1.0])\n"
    )
    paths = parallel_paths(source, helpers)
    assert paths["test_direct"] == ["COMM_WORLD"]
    assert paths["test_helper"] == ["_world -> COMM_WORLD"]
    assert paths["test_fixture"] == ["world -> COMM_WORLD"]
    assert paths["test_shared_dir"] == ["mpi_tmp_path"]
    assert paths["test_parametrized"] == ["COMM_WORLD"]
    assert paths["test_module_value"] == ["MESH -> COMM_WORLD"]
    assert paths["test_test_helper"] == ["check -> COMM_WORLD"]
    assert paths["test_runner"] == ["run_case"]
    assert paths["test_serial"] == []
    assert _one_rank_tests(ast.parse(source)) == {"test_direct"}
    assert _one_rank_tests(ast.parse("import pytest\npytestmark = [pytest.mark.one_rank(reason='x')]\n"
                                     "def test_a():\n    pass\n")) == {"test_a"}  # fmt: skip


@pytest.mark.parametrize("path", TEST_MODULES, ids=lambda p: p.stem)
def test_one_rank_tests_reach_no_parallel_code(path):
    """A test taken out of the runs on several ranks (``one_rank``) would silently stop testing
    the parallel code it reaches: it must reach none (:data:`PARALLEL_NAMES`); unmark it instead."""
    paths = parallel_paths(path.read_text(), HELPER_SOURCES)
    wrong = {name: paths[name] for name in sorted(_one_rank_tests(ast.parse(path.read_text()))) if paths[name]}
    assert not wrong, f"{path.name}: tests marked one_rank reach parallel code: {wrong}"


@dataclasses.dataclass
class _Item:
    """What conftest's check of ``parallel_twin`` reads of a collected test."""

    nodeid: str
    marks: tuple = ()

    def get_closest_marker(self, name: str):
        return next((mark for mark in self.marks if mark.name == name), None)


def test_a_parallel_twin_must_run_on_several_ranks():
    """A parameter set marked ``parallel_twin`` leaves the ranks' run only while its twin runs there:
    a twin that is itself marked, or that is not collected (renamed), stops the run."""
    from conftest import _check_twins

    config = type("Config", (), {"args": ["tests"]})()
    twin = pytest.mark.parallel_twin("a", reason="x").mark
    one_rank = pytest.mark.one_rank(reason="x").mark
    first, second = _Item("t.py::test_f[a]"), _Item("t.py::test_f[b]", (twin,))
    _check_twins(config, [first, second], [first])
    with pytest.raises(pytest.UsageError, match=r"test_f\[b\]: its parallel_twin t.py::test_f\[a\] does not run"):
        _check_twins(config, [_Item(first.nodeid, (one_rank,)), second], [])
    with pytest.raises(pytest.UsageError, match="parallel_twin"):
        _check_twins(config, [second], [])
    _check_twins(type("Config", (), {"args": ["t.py::test_f[b]"]})(), [second], [])  # the test chosen alone
    other = _Item("t.py::test_g", (pytest.mark.parallel_twin("test_f[a]", reason="x").mark,))
    _check_twins(config, [first, other], [first])  # a test of the module
    with pytest.raises(pytest.UsageError, match=r"test_g: its parallel_twin t.py::test_f\[b\] does not run"):
        _check_twins(config, [first, second, _Item("t.py::test_g", (pytest.mark.parallel_twin(
            "test_f[b]", reason="x").mark,))], [first])
