"""``NavSpec``: a planning and navigation benchmark spec (TOML) parsed and checked (pure).

::

    [benchmark]
    name = "nav-quick"
    seed = 7                          # scene seed and the pairs' stream
    pairs = 10                        # start-goal pairs per scene
    distance_m = [20.0, 60.0]         # straight-line start-goal distance range, within 20-500
    time_factor = 3.0                 # time limit: factor x shortest path / v_max + 60 s
    [[scenes]]
    name = "rocky"
    preset = "jezero-plain"           # or config = "scene.toml", or path = "built/scene"
    overrides = { rocks = { k = 0.08 } }
    soil = true                       # optional: the soil map on (or a ground soil's name)
    tau = 1.0                         # optional: dust optical depth
    [[methods]]
    name = "global-astar"             # kind defaults to the name
    [[methods]]
    name = "mine"
    kind = "controller"
    controller = "my_nav:Planner"     # MODULE:NAME, as `marsscene drive --controller`
    [[methods]]
    name = "ppo"
    kind = "policy"
    policy = "policy.npz"             # an MLPPolicy or CNNPolicy file (marsscene.env)

docs/benchmark_nav.md documents every key; every error is a one-line
:class:`~marsscene.errors.ConfigError`.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from marsscene._validate import check_range, dataclass_from_mapping, load_toml
from marsscene.errors import ConfigError

__all__ = ["DISTANCE_RANGE_M", "METHOD_KINDS", "NavMethodSpec", "NavSceneSpec", "NavSpec"]

#: The built-in methods, ``controller`` (a user's ``MODULE:NAME``) and ``policy`` (a trained
#: policy's ``.npz``).
METHOD_KINDS = ("straight", "global-astar", "orbital-astar", "arc-navigator", "controller",
                "policy")
#: The range start-goal distances may be drawn from (m).
DISTANCE_RANGE_M = (20.0, 500.0)


def _name_ok(name: object) -> bool:
    return isinstance(name, str) and bool(name) and all(c.isalnum() or c in "-_." for c in name)


@dataclass(frozen=True, kw_only=True)
class NavSceneSpec:
    """One scene: a preset, a scene config, a built scene folder or the default scene."""

    name: str
    preset: str | None = None
    config: str | None = None
    path: str | None = None
    """A built scene folder (``marsscene build``); used as it is."""
    overrides: dict[str, Any] = field(default_factory=dict)
    soil: bool | str = False
    """``true``: the scene's soil map on; a soil name: on, with that ground soil."""
    tau: float | None = None

    def __post_init__(self) -> None:
        if not _name_ok(self.name):
            raise ConfigError(f"scenes.name = {self.name!r}; use letters, digits, - _ .")
        given = [k for k in ("preset", "config", "path") if getattr(self, k) is not None]
        if len(given) > 1:
            raise ConfigError(f"scene {self.name!r}: give one of preset, config, path; got "
                              f"{given}")
        if self.path is not None and (self.overrides or self.soil or self.tau is not None):
            raise ConfigError(f"scene {self.name!r}: a built scene (path) takes no overrides, "
                              "soil or tau")
        if self.path is not None and not (Path(self.path) / "mjcf" / "scene.xml").is_file():
            raise ConfigError(f"scene {self.name!r}: {self.path} is not a built scene folder "
                              "(no mjcf/scene.xml)")
        if self.tau is not None:
            check_range(f"scene {self.name!r} tau", self.tau, 0.0, 50.0)

    def base_config(self) -> dict[str, Any]:
        """The scene-config mapping (preset or file, the overrides, soil and tau on top)."""
        from marsscene.config import read_config_toml
        from marsscene.sweep.spec import set_dotted

        base: dict[str, Any] = {}
        if self.preset is not None:
            base = {"preset": self.preset}
        elif self.config is not None:
            base = read_config_toml(str(self.config), what=f"scene {self.name!r} config")
        out = _merged(base, self.overrides)
        if self.soil:
            out = set_dotted(out, "soil.enabled", True)
            if isinstance(self.soil, str):
                out = set_dotted(out, "soil.ground", self.soil)
        if self.tau is not None:
            out = set_dotted(out, "lighting.tau", float(self.tau))
        export = dict(out.get("export", {}))
        export.setdefault("formats", ["mjcf"])  # episodes drive in MuJoCo
        out["export"] = export
        return out


def _merged(base: dict[str, Any], over: dict[str, Any]) -> dict[str, Any]:
    out = dict(base)
    for k, v in over.items():
        out[k] = _merged(out[k], v) if isinstance(v, dict) and isinstance(out.get(k),
                                                                          dict) else v
    return out


@dataclass(frozen=True, kw_only=True)
class NavMethodSpec:
    """One method: a built-in kind, ``controller`` with ``controller = "MODULE:NAME"``, or
    ``policy`` with ``policy`` a trained policy's ``.npz``."""

    name: str
    kind: str | None = None
    controller: str | None = None
    policy: str | None = None
    """``kind = "policy"``: the file of :meth:`MLPPolicy.save
    <marsscene.env.policy.MLPPolicy.save>` or :meth:`CNNPolicy.save
    <marsscene.env.cnn_policy.CNNPolicy.save>` (relative to the spec's folder)."""
    cost_weight: float = 4.0
    """Planners: a cell's step cost is its length x (1 + cost_weight x cost)."""

    def __post_init__(self) -> None:
        if not _name_ok(self.name):
            raise ConfigError(f"methods.name = {self.name!r}; use letters, digits, - _ .")
        kind = self.kind if self.kind is not None else self.name
        if kind not in METHOD_KINDS:
            raise ConfigError(f"method {self.name!r}: kind {kind!r} is not one of "
                              f"{', '.join(METHOD_KINDS)}")
        object.__setattr__(self, "kind", kind)
        if (kind == "controller") != (self.controller is not None):
            raise ConfigError(f"method {self.name!r}: controller = 'MODULE:NAME' goes with "
                              "kind = 'controller' (and only with it)")
        if (kind == "policy") != (self.policy is not None):
            raise ConfigError(f"method {self.name!r}: policy = 'FILE.npz' goes with "
                              "kind = 'policy' (and only with it)")
        if self.policy is not None and not Path(self.policy).is_file():
            raise ConfigError(f"method {self.name!r}: policy file {self.policy} not found")
        if self.controller is not None and ":" not in self.controller:
            raise ConfigError(f"method {self.name!r}: controller = {self.controller!r}; give "
                              "MODULE:NAME, e.g. my_nav:Planner")
        check_range(f"method {self.name!r} cost_weight", self.cost_weight, 0.0, 1e3)


@dataclass(frozen=True, kw_only=True)
class NavSpec:
    """A parsed navigation benchmark: scenes x pairs x methods."""

    scenes: tuple[NavSceneSpec, ...]
    methods: tuple[NavMethodSpec, ...]
    seed: int = 0
    pairs: int = 10
    distance_m: tuple[float, float] = (20.0, 100.0)
    time_factor: float = 3.0
    name: str = "nav"
    source: str = "<dict>"

    def __post_init__(self) -> None:
        if not self.scenes or not self.methods:
            raise ConfigError(f"{self.source}: needs at least one [[scenes]] and one "
                              "[[methods]] table")
        for what, names in (("scene", [s.name for s in self.scenes]),
                            ("method", [m.name for m in self.methods])):
            dupes = sorted({n for n in names if names.count(n) > 1})
            if dupes:
                raise ConfigError(f"{what} name {dupes[0]!r} is used twice")
        if isinstance(self.seed, bool) or not isinstance(self.seed, int) or self.seed < 0:
            raise ConfigError(f"benchmark.seed = {self.seed!r}; must be an integer >= 0")
        check_range("benchmark.pairs", self.pairs, 1, 10_000)
        d = tuple(float(v) for v in self.distance_m)
        lo, hi = DISTANCE_RANGE_M
        if len(d) != 2 or not lo <= d[0] <= d[1] <= hi:
            raise ConfigError(f"benchmark.distance_m = {list(self.distance_m)!r}; need [min, "
                              f"max] with {lo:g} <= min <= max <= {hi:g}")
        object.__setattr__(self, "distance_m", d)
        check_range("benchmark.time_factor", self.time_factor, 1.0, 100.0)

    @classmethod
    def from_dict(cls, data: dict[str, Any], *, base_dir: Path | None = None,
                  source: str = "<dict>") -> NavSpec:
        """Check a parsed spec mapping; relative config / path entries resolve against
        ``base_dir`` (default: the current folder)."""
        unknown = sorted(set(data) - {"benchmark", "scenes", "methods"})
        if unknown:
            raise ConfigError(f"{source}: unknown table(s) {unknown}; allowed: benchmark, "
                              "scenes, methods")
        bench = data.get("benchmark", {})
        if not isinstance(bench, dict):
            raise ConfigError(f"[benchmark] must be a table; got {bench!r}")
        allowed = {"name", "seed", "pairs", "distance_m", "time_factor"}
        if set(bench) - allowed:
            raise ConfigError(f"unknown key benchmark.{sorted(set(bench) - allowed)[0]}; "
                              f"allowed: {sorted(allowed)}")
        bench = dict(bench)
        if "distance_m" in bench:
            if not isinstance(bench["distance_m"], list):
                raise ConfigError(f"benchmark.distance_m = {bench['distance_m']!r}; must be "
                                  "[min, max]")
            bench["distance_m"] = tuple(bench["distance_m"])
        here = base_dir or Path.cwd()
        scenes = []
        for i, raw in enumerate(data.get("scenes") or ()):
            if not isinstance(raw, dict):
                raise ConfigError(f"scenes[{i}] must be a table; got {raw!r}")
            raw = dict(raw)
            for key in ("config", "path"):
                if isinstance(raw.get(key), str):
                    raw[key] = str((here / raw[key]).resolve())
            scene = dataclass_from_mapping(NavSceneSpec, raw, f"scenes[{i}]")
            if scene.path is None:
                _check_config(scene)
            scenes.append(scene)
        methods = []
        for i, raw in enumerate(data.get("methods") or ()):
            if not isinstance(raw, dict):
                raise ConfigError(f"methods[{i}] must be a table; got {raw!r}")
            raw = dict(raw)
            if isinstance(raw.get("policy"), str):
                raw["policy"] = str((here / raw["policy"]).resolve())
            methods.append(dataclass_from_mapping(NavMethodSpec, raw, f"methods[{i}]"))
        return cls(scenes=tuple(scenes), methods=tuple(methods), source=source, **bench)

    @classmethod
    def from_toml(cls, path: str | Path) -> NavSpec:
        """Read and check a spec TOML (relative paths resolve against its folder)."""
        p = Path(path)
        return cls.from_dict(load_toml(p, what="benchmark spec"), base_dir=p.parent.resolve(),
                             source=str(p))

    def doc(self) -> dict[str, Any]:
        """The spec as JSON-able data (``benchmark.json``; a resumed run must match it)."""
        import json

        d = dataclasses.asdict(self)
        d.pop("source", None)
        return dict(json.loads(json.dumps(d, default=str)))


def _check_config(scene: NavSceneSpec) -> None:
    from marsscene.config import SceneConfig

    try:  # a bad preset, file or override fails here, before any episode runs
        SceneConfig.from_dict(scene.base_config())
    except ConfigError as err:
        raise ConfigError(f"scene {scene.name!r}: {err}") from None
