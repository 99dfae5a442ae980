"""Audit (session 48): rrtdrive as a user gets it, a wheel and an sdist, not the editable checkout.

One module-scoped build makes an sdist and a wheel from a copy of the working tree (git's
tracked and untracked-but-not-ignored files, never the checkout itself, so no build/ or
egg-info lands in it), then a second wheel from the unpacked sdist. The wheel is installed
with ``pip --no-deps --no-index --target`` (the test interpreter supplies the dependencies)
and driven from an unrelated directory, so the repository is not on ``sys.path``.

Building needs setuptools >= 77 (pyproject's ``license = "MIT"``, PEP 639): the test
interpreter's own if it has it, else a throw-away venv that pip fills from its index; the
tests skip when neither works (offline with an old setuptools).
"""

from __future__ import annotations

import ast
import email
import hashlib
import json
import os
import pathlib
import shutil
import subprocess
import sys
import tarfile
import tomllib
import zipfile

import pytest

ROOT = pathlib.Path(__file__).resolve().parent.parent
PYPROJECT = tomllib.loads((ROOT / "pyproject.toml").read_text())
VERSION = PYPROJECT["project"]["version"]
#: Where each installed package's source lives in the repository.
SOURCE_DIRS = {"rrtdrive": ROOT / "src" / "rrtdrive", "rrtdrive/envs": ROOT / "envs",
               "rrtdrive/controllers": ROOT / "controllers"}
HEAVY = ("highway_env", "matplotlib", "pygame", "ompl", "ray", "commonroad", "commonroad_dc",
         "control", "stable_baselines3", "torch", "imageio", "PIL", "yaml")
TIMEOUT = 120


def _run(cmd: list[str], **kw) -> subprocess.CompletedProcess[str]:
    return subprocess.run(cmd, capture_output=True, text=True, timeout=TIMEOUT, **kw)


def _has_backend(python: str) -> bool:
    probe = ("import setuptools, wheel; "
             "raise SystemExit(int(setuptools.__version__.split('.')[0]) < 77)")
    return _run([python, "-c", probe]).returncode == 0


def _source_files() -> list[str]:
    if not (ROOT / ".git").exists() or shutil.which("git") is None:
        pytest.skip("needs a git checkout to copy the working tree")
    out = _run(["git", "ls-files", "--cached", "--others", "--exclude-standard", "-z"], cwd=ROOT)
    if out.returncode != 0:
        pytest.skip(f"git ls-files failed: {out.stderr.strip()}")
    names = [n for n in out.stdout.split("\0") if n]
    # results/ is 100 MB of measurements no build reads; a deleted but unstaged file is gone.
    return [n for n in names if not n.startswith("results/") and (ROOT / n).is_file()]


def _build(python: str, how: str, src: pathlib.Path, out: pathlib.Path) -> pathlib.Path:
    out.mkdir(parents=True, exist_ok=True)
    script = (f"import os, setuptools.build_meta as b; os.chdir({str(src)!r}); "
              f"print(b.build_{how}({str(out)!r}))")
    res = _run([python, "-c", script])
    assert res.returncode == 0, res.stderr[-3000:]
    return out / res.stdout.strip().splitlines()[-1]


@pytest.fixture(scope="module")
def dists(tmp_path_factory: pytest.TempPathFactory) -> dict[str, pathlib.Path]:
    tmp = tmp_path_factory.mktemp("pkg")
    tree = tmp / "tree"
    for name in _source_files():
        target = tree / name
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(ROOT / name, target)
    python = sys.executable
    if not _has_backend(python):
        env_dir = tmp / "buildenv"
        made = _run([sys.executable, "-m", "venv", str(env_dir)])
        python = str(env_dir / "bin" / "python")
        if made.returncode != 0 or _run(
            [python, "-m", "pip", "install", "-q", "setuptools>=77", "wheel"]
        ).returncode != 0 or not _has_backend(python):
            pytest.skip("no setuptools>=77 here and pip could not fetch it")
    sdist = _build(python, "sdist", tree, tmp / "dist")
    wheel = _build(python, "wheel", tree, tmp / "dist")
    with tarfile.open(sdist) as tf:
        tf.extractall(tmp / "unpacked", filter="data")
    (unpacked,) = (tmp / "unpacked").iterdir()
    wheel_from_sdist = _build(python, "wheel", unpacked, tmp / "dist_from_sdist")
    return {"sdist": sdist, "wheel": wheel, "wheel_from_sdist": wheel_from_sdist,
            "tmp": tmp}


@pytest.fixture(scope="module")
def wheel_names(dists) -> set[str]:
    return set(zipfile.ZipFile(dists["wheel"]).namelist())


@pytest.fixture(scope="module")
def sdist_names(dists) -> set[str]:
    with tarfile.open(dists["sdist"]) as tf:
        return {m.name.partition("/")[2] for m in tf.getmembers() if m.isfile()}


@pytest.fixture(scope="module")
def installed(dists) -> dict[str, object]:
    """The wheel installed with --target; a runner for commands from an unrelated folder."""
    tmp = dists["tmp"]
    target = tmp / "site"
    res = _run([sys.executable, "-m", "pip", "install", "-q", "--no-deps", "--no-index",
                "--target", str(target), str(dists["wheel"])])
    assert res.returncode == 0, res.stderr[-2000:]
    work = tmp / "elsewhere"
    work.mkdir()
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PYTHONSTARTUP")}
    env["PYTHONPATH"] = str(target)
    env["PYTHONSAFEPATH"] = "1"  # python -c / -m: no cwd on sys.path either

    def run(*args: str) -> subprocess.CompletedProcess[str]:
        return _run(list(args), cwd=work, env=env)

    return {"target": target, "work": work, "run": run}


def _py(installed, code: str) -> subprocess.CompletedProcess[str]:
    return installed["run"](sys.executable, "-c", code)


# ---------------------------------------------------------------------------- the wheel


def test_wheel_holds_every_source_file_under_rrtdrive(wheel_names):
    expected = set()
    for prefix, folder in SOURCE_DIRS.items():
        for path in folder.rglob("*"):
            if path.is_file() and "__pycache__" not in path.parts and path.suffix != ".pyc":
                rel = path.relative_to(folder).as_posix()
                if prefix == "rrtdrive" or not rel.startswith("data/"):
                    expected.add(f"{prefix}/{rel}")
    payload = {n for n in wheel_names if ".dist-info/" not in n}
    assert expected - payload == set()
    assert payload - expected == set()
    assert {n.split("/")[0] for n in payload} == {"rrtdrive"}  # no top-level envs/ controllers/


def test_wheel_ships_py_typed_and_every_data_map(wheel_names):
    assert "rrtdrive/py.typed" in wheel_names
    maps = {p.name for p in (ROOT / "src/rrtdrive/data/maps").glob("*.json")}
    assert maps  # the tight maps live as files
    assert {n.rpartition("/")[2] for n in wheel_names
            if n.startswith("rrtdrive/data/maps/")} == maps


def test_wheel_metadata_matches_pyproject(dists):
    zf = zipfile.ZipFile(dists["wheel"])
    info = f"rrtdrive-{VERSION}.dist-info"
    meta = email.message_from_string(zf.read(f"{info}/METADATA").decode())
    assert meta["Name"] == "rrtdrive"
    assert meta["Version"] == VERSION
    assert meta["Requires-Python"] == PYPROJECT["project"]["requires-python"]
    base = {r.replace(" ", "") for r in meta.get_all("Requires-Dist") if "extra ==" not in r}
    assert base == {d.replace(" ", "") for d in PYPROJECT["project"]["dependencies"]}
    assert set(meta.get_all("Provides-Extra")) == set(PYPROJECT["project"]["optional-dependencies"])
    entry = zf.read(f"{info}/entry_points.txt").decode()
    assert "rrtdrive = rrtdrive.cli:main" in entry
    assert zf.read(f"{info}/top_level.txt").decode().split() == ["rrtdrive"]


def test_version_attribute_matches_pyproject():
    tree = ast.parse((ROOT / "src/rrtdrive/__init__.py").read_text())
    values = [node.value.value for node in tree.body if isinstance(node, ast.Assign)
              and any(getattr(t, "id", None) == "__version__" for t in node.targets)]
    assert values == [VERSION]


# ----------------------------------------------------------------------------- the sdist


def test_sdist_has_what_a_build_needs(sdist_names, wheel_names):
    for needed in ("pyproject.toml", "README.md", "PKG-INFO"):
        assert needed in sdist_names
    for lic in ROOT.glob("LICEN[CS]E*"):
        assert lic.name in sdist_names
    sources = {"rrtdrive": "src/rrtdrive", "rrtdrive/envs": "envs",
               "rrtdrive/controllers": "controllers"}
    for name in wheel_names:
        if ".dist-info/" in name:
            continue
        prefix = max((p for p in sources if name.startswith(p + "/")), key=len)
        assert name.replace(prefix, sources[prefix], 1) in sdist_names, name


def test_wheel_from_sdist_is_the_wheel_from_the_tree(dists):
    def payload(path: pathlib.Path) -> dict[str, str]:
        zf = zipfile.ZipFile(path)
        return {n: hashlib.sha256(zf.read(n)).hexdigest() for n in zf.namelist()
                if not n.endswith(".dist-info/RECORD")}

    assert payload(dists["wheel_from_sdist"]) == payload(dists["wheel"])


def test_wheel_and_sdist_carry_the_licence_text(wheel_names, sdist_names):
    # pyproject says MIT, whose terms ask for the text to travel with every copy.
    assert "LICENSE" in sdist_names
    assert any(n.endswith(".dist-info/licenses/LICENSE") for n in wheel_names), sorted(
        n for n in wheel_names if ".dist-info/" in n
    )


def test_sdist_tests_are_whole_or_absent(sdist_names):
    shipped = {n for n in sdist_names if n.startswith("tests/")}
    if not shipped:
        return
    support = {p.relative_to(ROOT).as_posix() for p in (ROOT / "tests").glob("*.py")
               if not p.name.startswith("test_")}
    assert support  # conftest.py and the helpers the tests import
    assert support <= shipped


# ---------------------------------------------------------------- the installed wheel


def test_installed_package_is_the_wheel_not_the_checkout(installed):
    res = _py(installed, (
        "import json, sys, rrtdrive, rrtdrive.envs, rrtdrive.controllers, rrtdrive.data.maps\n"
        "print(json.dumps([m.__file__ for m in (rrtdrive, rrtdrive.envs, "
        "rrtdrive.controllers)] + [str(p) for p in rrtdrive.data.maps.__path__]))"))
    assert res.returncode == 0, res.stderr
    target = str(installed["target"])
    for path in json.loads(res.stdout):
        assert path.startswith(target), path
    assert not _py(installed, "import envs").returncode == 0
    assert not _py(installed, "import controllers").returncode == 0


def test_installed_version_matches_metadata(installed):
    script = installed["target"] / "bin" / "rrtdrive"
    outs = [installed["run"](str(script), "--version"),
            installed["run"](sys.executable, "-m", "rrtdrive", "--version")]
    meta = _py(installed, "import importlib.metadata as m, rrtdrive; "
                          "print(m.version('rrtdrive'), rrtdrive.__version__)")
    assert meta.stdout.split() == [VERSION, VERSION]
    for res in outs:
        assert res.returncode == 0, res.stderr
        assert res.stdout.strip() == f"rrtdrive {VERSION}"


@pytest.mark.parametrize("command", ["", "plan", "maps", "verify", "simulate", "bench"])
def test_installed_help_of_every_command(installed, command):
    cmd = [str(installed["target"] / "bin" / "rrtdrive")]
    if not command:  # python -m rrtdrive is the same parser
        cmd = [sys.executable, "-m", "rrtdrive"]
    res = installed["run"](*cmd, *command.split(), "--help")
    assert res.returncode == 0, res.stderr
    assert res.stdout.startswith(f"usage: rrtdrive {command}".rstrip())
    assert not res.stderr


def test_installed_builtin_maps_list_load_and_export(installed):
    res = _py(installed, (
        "import json, rrtdrive\n"
        "from importlib.resources import files\n"
        "maps = {n: len(rrtdrive.builtin_map(n).obstacles) for n in rrtdrive.BUILTIN_MAPS}\n"
        "data = sorted(p.name for p in files('rrtdrive.data.maps').iterdir()"
        " if p.name.endswith('.json'))\n"
        "print(json.dumps([maps, data]))"))
    assert res.returncode == 0, res.stderr
    maps, data = json.loads(res.stdout)
    assert {pathlib.Path(n).stem for n in data} <= set(maps)
    assert all(count > 0 for count in maps.values())
    listing = installed["run"](str(installed["target"] / "bin" / "rrtdrive"), "maps",
                               "--export", "exported")
    assert listing.returncode == 0, listing.stderr
    assert [line.split()[0] for line in listing.stdout.splitlines()] == list(maps)
    for name in maps:
        doc = json.loads((installed["work"] / "exported" / f"{name}.json").read_text())
        assert len(doc["obstacles"]) == maps[name]


def test_installed_plan_and_verify_on_a_data_map(installed):
    script = str(installed["target"] / "bin" / "rrtdrive")
    res = installed["run"](script, "plan", "garage", "--json", "garage.json")
    assert res.returncode == 0, res.stderr
    doc = json.loads((installed["work"] / "garage.json").read_text())
    assert doc["success"] and doc["map"] == "garage" and doc["map_file"] is None
    check = installed["run"](script, "verify", "garage.json")
    assert check.returncode == 0, check.stdout + check.stderr


def test_import_rrtdrive_loads_no_heavy_module(installed):
    res = _py(installed, (
        "import sys, rrtdrive, rrtdrive.envs, rrtdrive.controllers, rrtdrive.planning\n"
        f"heavy = {HEAVY!r}\n"
        "print(sorted({m.split('.')[0] for m in sys.modules} & set(heavy)))"))
    assert res.returncode == 0, res.stderr
    assert res.stdout.strip() == "[]"


def test_installed_gym_ids_make_and_check(installed):
    res = _py(installed, (
        "import warnings; warnings.simplefilter('ignore')\n"
        "import json, gymnasium as gym, rrtdrive, sys\n"
        "from gymnasium.utils.env_checker import check_env\n"
        "out = {}\n"
        "for eid in rrtdrive.ENV_IDS:\n"
        "    env = gym.make(eid)\n"
        "    out[eid] = sys.modules[type(env.unwrapped).__module__].__file__\n"
        "    env.close()\n"
        "env = gym.make('rrtdrive/Overtake-v0')\n"
        "env.reset(seed=0); env.step(env.action_space.sample())\n"
        "check_env(env.unwrapped, skip_render_check=True)\n"
        "env = gym.make('rrtdrive:rrtdrive/Map-v0', scenario='reverse_bay',"
        " scenario_options={'reverse': True})\n"
        "out['prefixed'] = env.spec.entry_point\n"
        "print(json.dumps(out))"))
    assert res.returncode == 0, res.stderr[-3000:]
    files = json.loads(res.stdout.splitlines()[-1])
    # "rrtdrive:rrtdrive/Map-v0" imports rrtdrive by itself; a data map by name.
    assert files.pop("prefixed") == "rrtdrive.envs.drive_env:DriveEnv"
    documented = ("Parking-v0", "ParkingReverseIn-v0", "Overtake-v0", "OvertakeTraffic-v0",
                  "ParallelParking-v0", "UTurn-v0", "Map-v0")
    assert set(files) == {f"rrtdrive/{name}" for name in documented}
    assert all(f.startswith(str(installed["target"])) for f in files.values())
