"""The package's layout as docs/layout.md draws it: a few modules at the top, subpackages by stage,
imports that run one way (no circles, no arrow back up a stage), shared pieces public."""

import ast
import re
import subprocess
import sys
from pathlib import Path

import egosearch

PACKAGE = Path(egosearch.__file__).resolve().parent
LAYOUT_MD = PACKAGE.parent / "docs" / "layout.md"

LAYERS = {
    "core": set(),
    "scene": set(),
    "sim": {"core", "scene"},
    "searchers": {"core", "scene", "sim"},
    "envs": {"core", "scene", "sim", "searchers"},
    "runs": {"core", "scene", "sim", "searchers", "envs"},
    "rl": {"core", "scene", "sim", "searchers", "envs", "runs"},
    "motion": {"core", "scene", "sim", "searchers", "envs", "runs"},
    "report": {"core", "scene"},
    "variants": {"core", "scene", "sim", "envs", "rl"},
    "workflow": {"core", "scene", "variants", "report"},
    "cost": {"core", "rl", "variants", "report", "workflow"},
    "cli": {"core", "scene", "sim", "searchers", "envs", "runs", "rl", "motion", "report", "variants", "workflow",
            "cost"},
    # the package's __init__: it registers the gymnasium ids (egosearch.envs) where gymnasium is loaded, for
    # gymnasium.make("egosearch:EgoSearch-v0"), and imports nothing else
    "(root)": {"envs"},
}
"""Each stage and the stages it may import: the pipeline's order (scene -> sim -> searchers -> envs (every
gymnasium id and the env options, ``egosearch/envs.py``) -> runs -> rl -> motion), the report layer apart
(files in, files out), variants, the workflow, the cost model (it
simulates the workflow's DAG: the env step units of rl, a comparison's variant, the report's readers of
the workflow's config and stored jobs) and the CLI on top."""


OPEN_MODULES = {"egosearch.searchers.searcher_registry", "egosearch.core.named_registry"}
"""Modules every stage may import, whatever their stage: plain data that imports no other module of egosearch
but another open one, nor any package outside the standard library (checked below), so that reading one loads
no stage. The searchers' registry: the report's tables and figures, the workflow's checks and rules and the
variants read which searchers there are from it, the one place a searcher is added. The registry helper both
registries use."""


def _module_name(path: Path) -> str:
    parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _package_of(path: Path) -> str:
    """The package a module's relative imports start from: its own for an ``__init__``, else its parent's."""
    return ".".join(path.relative_to(PACKAGE.parent).parent.parts)


def _imports_of(path: Path) -> list[tuple[str, str]]:
    return _imports(path.read_text(), _package_of(path))


def _imports(source: str, package: str = "egosearch") -> list[tuple[str, str]]:
    """(imported egosearch module, imported name or '') of every import in ``source``, those under
    ``if TYPE_CHECKING:`` and inside functions included: an annotation's import is an arrow too. A relative
    import is resolved against ``package``, the package the source's module is in."""
    out = []
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.ImportFrom) and node.level:
            base = package.split(".")[: len(package.split(".")) - (node.level - 1)]
            module = ".".join(base + ([node.module] if node.module else []))
            out += [(module, a.name) for a in node.names]
        elif isinstance(node, ast.ImportFrom) and node.module and node.module.startswith("egosearch"):
            out += [(node.module, a.name) for a in node.names]
        elif isinstance(node, ast.Import):
            out += [(a.name, "") for a in node.names if a.name.startswith("egosearch")]
    return out


def _modules() -> dict[str, Path]:
    return {_module_name(p): p for p in PACKAGE.rglob("*.py")}


def _stage(module: str) -> str:
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else "(root)"


def _target(imported: str, name: str, modules: dict) -> str:
    full = f"{imported}.{name}"
    return full if full in modules else imported


def test_the_top_of_the_package_holds_few_modules_and_every_subpackage_says_what_it_holds():
    top = sorted(p.name for p in PACKAGE.glob("*.py"))
    assert len(top) <= 8, top
    for init in PACKAGE.glob("*/__init__.py"):
        doc = ast.get_docstring(ast.parse(init.read_text()))
        assert doc and "import" in doc.splitlines()[1].lower(), f"{init}: its docstring's 2nd line says who imports it"
    assert set(LAYERS) >= {p.parent.name for p in PACKAGE.glob("*/__init__.py")} | {"variants"}


def test_imports_under_type_checking_and_in_functions_count():
    source = ("from typing import TYPE_CHECKING\n"
              "if TYPE_CHECKING:\n    from egosearch.variants import ResolvedVariant\n"
              "def f():\n    import egosearch.sim.body_envs\n")
    assert _imports(source) == [("egosearch.variants", "ResolvedVariant"), ("egosearch.sim.body_envs", "")]
    # a relative import is an arrow too, resolved from the module's package
    assert _imports("from ..variants import load_variant\nfrom . import envs\n", "egosearch.rl") == [
        ("egosearch.variants", "load_variant"), ("egosearch.rl", "envs")]


def test_each_stage_imports_only_the_stages_below_it():
    modules = _modules()
    wrong = []
    for name, path in modules.items():
        stage = _stage(name)
        for imported, item in _imports_of(path):
            target = _target(imported, item, modules)
            other = _stage(target)
            if other not in (stage, "(root)") and other not in LAYERS[stage] and target not in OPEN_MODULES:
                wrong.append(f"{name} -> {imported}")
    assert not wrong, wrong


def test_an_open_module_and_its_package_import_only_the_standard_library():
    """What makes a module open to every stage: importing it (and its package's ``__init__``) loads nothing
    else of egosearch but other open modules, and no third-party package (numpy, torch, the simulator)."""
    modules = _modules()
    allowed = set(sys.stdlib_module_names) | {"__future__"}
    for name in OPEN_MODULES:
        for module in (name, name.rsplit(".", 1)[0]):
            tree = ast.parse(modules[module].read_text())
            imported = {a.name for node in ast.walk(tree) if isinstance(node, ast.Import) for a in node.names}
            imported |= {node.module for node in ast.walk(tree)
                         if isinstance(node, ast.ImportFrom) and node.module and not node.level}
            outside = {i for i in imported if i.split(".")[0] not in allowed and i not in OPEN_MODULES}
            assert not outside, (module, sorted(outside))
    # and so, run: a fresh process that imports them has loaded no third-party package
    probe = ("import importlib, sys\n"
             f"for name in {sorted(OPEN_MODULES)!r}:\n    importlib.import_module(name)\n"
             "print(sorted(m for m in sys.modules if m.split('.')[0] in ('numpy', 'torch', 'pybullet', 'scipy')))")
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]", out


def find_cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """Every circle a depth-first walk of ``graph`` meets, as the path that closes it."""
    state: dict[str, int] = {}
    found: list[list[str]] = []

    def visit(node: str, stack: list[str]) -> None:
        state[node] = 1
        for nxt in sorted(graph.get(node, ())):
            if state.get(nxt) == 1:
                found.append(stack[stack.index(nxt):] + [nxt])
            elif nxt not in state:
                visit(nxt, stack + [nxt])
        state[node] = 2

    for node in sorted(graph):
        if node not in state:
            visit(node, [node])
    return found


RULE_FILES = [PACKAGE.parent / "Snakefile", *sorted((PACKAGE / "workflow" / "rules").glob("*.smk"))]
RULES_MAY_IMPORT = {"core", "scene", "variants", "report", "workflow", "cost"}
"""What the Snakefile and the rules (``workflow/rules/*.smk``) may import: the workflow's own stage and what it
reads (its checks, the report's readers of stored jobs, the variants, the scene's home splits), the cost model
(the dry run's cost line) and the shared plumbing; never a stage that loads torch or the simulator, which
every ``snakemake`` call, a dry run included, would then pay for."""


def _rule_imports(path: Path) -> list[tuple[str, str]]:
    """The egosearch imports of a Snakefile or ``.smk`` file, at its top and inside its functions: the file is
    no Python module (rule blocks), so each import statement is read on its own."""
    statements, pending = [], ""
    for line in path.read_text().splitlines():
        stripped = line.strip()
        if pending:
            pending += " " + stripped
        elif re.match(r"(from|import)\s+egosearch\b", stripped):
            pending = stripped
        if pending and (pending.count("(") == pending.count(")")):
            statements.append(pending)
            pending = ""
    return [pair for statement in statements for pair in _imports(statement)]


def test_the_rules_read_the_package_without_torch_or_the_simulator():
    assert ("egosearch.workflow.check", "checked_variants") in _rule_imports(RULE_FILES[0])
    modules = _modules()
    seen, wrong = set(), []
    for path in RULE_FILES:
        for imported, item in _rule_imports(path):
            target = _target(imported, item, modules)
            seen.add(target if target in modules else imported)
            if _stage(target) not in RULES_MAY_IMPORT and target not in OPEN_MODULES:
                wrong.append(f"{path.name} -> {imported}")
    assert not wrong, wrong
    assert len(seen) >= 10  # the reader found the rules' imports (common.smk alone has more)
    # what the layers promise, run: importing everything the rules import loads neither torch nor pybullet
    probe = ("import importlib, sys\n"
             f"for name in {sorted(seen)!r}:\n    importlib.import_module(name)\n"
             "print(sorted(m for m in ('torch', 'pybullet') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]", out


def test_no_import_circles():
    assert find_cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c", "a"]]
    modules = _modules()
    graph = {name: {_target(i, n, modules) for i, n in _imports_of(path)} & set(modules) - {name}
             for name, path in modules.items()}
    assert not find_cycles(graph)


def test_the_stage_rules_themselves_run_one_way():
    """No two stages may import each other, even through others: modules free of circles could still
    hide one between stages (the cost model reads the workflow, so the workflow and report may not read it)."""
    assert not find_cycles({stage: allowed - {stage} for stage, allowed in LAYERS.items()})


def test_no_module_imports_another_modules_private_names():
    modules = _modules()
    private = [f"{name} imports {imported}.{item}" for name, path in modules.items()
               for imported, item in _imports_of(path)
               if item.startswith("_") and not item.startswith("__") and imported != name]
    assert not private, private


def _drawn_tree() -> dict[str, list[str]]:
    """docs/layout.md's drawing of the package: each top-level row's name ('' for the package's own
    files) -> the lines drawn under it, itself included."""
    drawing = LAYOUT_MD.read_text().split("```")[1]
    sections: dict[str, list[str]] = {}
    current = ""
    for line in drawing.splitlines():
        top = re.match(r"[├└]── (\S+)", line)
        if top:
            current = top.group(1).rstrip("/") if top.group(1).endswith("/") else ""
        sections.setdefault(current, []).append(line)
    return sections


def _registered_modules() -> set[str]:
    """The modules a registry names (a learner's agent, settings and actor loaders; a searcher's factory; an
    observation option's classes):
    the registry is their listing, so a plug-in is its file and its registration line, with no drawing or
    docstring to edit."""
    from egosearch.rl.learner_registry import LEARNERS
    from egosearch.searchers.searcher_registry import SEARCHERS
    from egosearch.sim.observation_options import OPTIONS

    targets = [t for e in LEARNERS.values() for t in (e.agent, e.settings, *e.actor_formats.values())]
    targets += [e.factory for e in SEARCHERS.values()]
    targets += [t for e in OPTIONS.values() for t in (e.option, e.settings)]
    return {t.partition(":")[0] for t in targets if isinstance(t, str)}


def test_the_registries_name_modules_that_exist():
    registered = _registered_modules()
    assert {"egosearch.rl.sac_drq", "egosearch.searchers.frontier", "egosearch.sim.contact_signal"} <= registered
    for module in registered:
        assert (PACKAGE.parent / (module.replace(".", "/") + ".py")).is_file(), module


def test_layout_md_draws_every_stage_and_every_module_of_the_stages_it_draws_module_by_module():
    sections = _drawn_tree()
    assert set(sections) - {""} == {p.parent.name for p in PACKAGE.glob("*/__init__.py")}
    for stage, lines in sections.items():
        folder = PACKAGE / stage
        named = {name for line in lines for name in re.findall(r"\b(\w+\.(?:py|c))\b", line)}
        assert all((folder / name).is_file() for name in named), (stage, sorted(n for n in named
                                                                                 if not (folder / n).is_file()))
        # a stage drawn module by module (rows of their own under it) names all its modules
        if stage == "" or any(re.match(r"│   [├└]── ", line) for line in lines):
            modules = {p.name for p in folder.glob("*.py")} - ({"__init__.py"} if stage else set())
            # a module a registry names may be left out: its registration line lists it
            plugins = {m.rsplit(".", 1)[1] + ".py" for m in _registered_modules() if m.rsplit(".", 1)[0] ==
                       ".".join(filter(None, ["egosearch", stage]))}
            assert modules - plugins <= named, (stage or "egosearch/", sorted(modules - plugins - named))


def test_a_packages_docstring_that_lists_its_modules_lists_all_of_them():
    checked = 0
    for init in PACKAGE.glob("*/__init__.py"):
        doc = ast.get_docstring(ast.parse(init.read_text())) or ""
        if not re.search(r"^- :mod:", doc, re.MULTILINE):
            continue
        package = init.parent.name
        listed = set(re.findall(rf":mod:`~?egosearch\.{package}\.(\w+)`", doc))
        modules = {p.stem for p in init.parent.glob("*.py")} - {"__init__"}
        plugins = {m.rsplit(".", 1)[1] for m in _registered_modules() if m.rsplit(".", 1)[0] == f"egosearch.{package}"}
        missing, gone = modules - plugins - listed, listed - modules
        assert not missing and not gone, (package, "missing:", sorted(missing), "gone:", sorted(gone))
        checked += 1
    assert checked >= 2  # rl and motion list theirs


NOTE_LINE = re.compile(r"^(Imports|Imported by|Packages): (?P<names>[^.]*)\.\s*$", re.MULTILINE)


def _third_party(path: Path) -> set[str]:
    out = set()
    for node in ast.walk(ast.parse(path.read_text())):
        names = [a.name for a in node.names] if isinstance(node, ast.Import) else (
            [node.module] if isinstance(node, ast.ImportFrom) and not node.level and node.module else [])
        out |= {n.split(".")[0] for n in names}
    return out - set(sys.stdlib_module_names) - {"__future__", "egosearch"}


def test_each_package_note_says_what_it_imports_what_imports_it_and_which_packages_it_uses():
    """Each package's docstring has the lines ``Imports:``, ``Imported by:`` and ``Packages:`` (names, or
    "nothing" / "none"), and they are the import graph's: the stages its modules import (the searchers' registry
    counts as searchers), the stages and the Snakefile's rules that import one of its modules, and the packages
    outside the standard library its modules import."""
    modules = _modules()
    imports: dict[str, set[str]] = {}
    imported_by: dict[str, set[str]] = {}
    packages: dict[str, set[str]] = {}
    for name, path in modules.items():
        stage = _stage(name)
        packages.setdefault(stage, set()).update(_third_party(path))
        for imported, item in _imports_of(path):
            other = _stage(_target(imported, item, modules))
            if other != stage:
                imports.setdefault(stage, set()).add(other)
                imported_by.setdefault(other, set()).add(stage)
    for path in RULE_FILES:
        for imported, item in _rule_imports(path):
            imported_by.setdefault(_stage(_target(imported, item, modules)), set()).add("Snakefile")
    wrong = []
    for init in sorted(PACKAGE.glob("*/__init__.py")):
        stage = init.parent.name
        said = {kind: set() if names.strip() in ("nothing", "none") else {n.strip() for n in names.split(",")}
                for kind, names in NOTE_LINE.findall(ast.get_docstring(ast.parse(init.read_text())) or "")}
        true = {"Imports": imports.get(stage, set()), "Imported by": imported_by.get(stage, set()),
                "Packages": packages.get(stage, set())}
        for kind, names in true.items():
            if said.get(kind) != names:
                wrong.append(f"{init.relative_to(PACKAGE.parent)} {kind}: says {sorted(said.get(kind, {'(no line)'}))}"
                             f", is {sorted(names)}")
    assert not wrong, "\n".join(wrong)
