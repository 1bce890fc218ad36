"""``marsscene eval``: ATE and RPE of an estimated trajectory against ground truth (TUM files)."""

from __future__ import annotations

import json
from pathlib import Path

import click

from marsscene.cli._common import user_errors

_PATH = click.Path(exists=True, dir_okay=False, path_type=Path)


@click.command(name="eval", short_help="ATE/RPE of EST.tum against GT.tum (Umeyama aligned).")
@click.argument("est", type=_PATH)
@click.argument("gt", type=_PATH)
@click.option(
    "--align",
    type=click.Choice(["se3", "sim3", "none"]),
    default="se3",
    show_default=True,
    help="Alignment of EST onto GT before ATE (sim3: monocular).",
)
@click.option(
    "--max-dt-s",
    "max_dt",
    type=click.FloatRange(min=0),
    default=0.01,
    show_default=True,
    help="Largest timestamp difference for association (s).",
)
@click.option(
    "--delta",
    type=click.IntRange(min=1),
    default=1,
    show_default=True,
    help="RPE step in associated frames.",
)
@click.option("--json", "as_json", is_flag=True, help="Print the results as JSON.")
def eval_cmd(est: Path, gt: Path, align: str, max_dt: float, delta: int, as_json: bool) -> None:
    """Print ATE (RMSE after alignment) and RPE (translation, rotation) of EST against GT.

    \b
    Example:
      marsscene eval runs/r1/odom.tum runs/r1/gt.tum
    """
    from marsscene.runtime import ate, read_tum, rpe

    with user_errors():
        e, g = read_tum(est), read_tum(gt)
        a = ate(e, g, align=align, max_dt_s=max_dt)
        r = rpe(e, g, delta_frames=delta, max_dt_s=max_dt)
    if as_json:
        doc = {
            "ate_m": a.stats.as_dict(),
            "scale": a.scale,
            "rpe_translation_m": r.translation.as_dict(),
            "rpe_rotation_deg": r.rotation_deg.as_dict(),
        }
        click.echo(json.dumps(doc, indent=2, sort_keys=True))
        return
    st = a.stats
    click.echo(
        f"pairs: {st.n}   alignment: {align}"
        + (f" (scale {a.scale:.6f})" if align == "sim3" else "")
    )
    click.echo(
        f"ATE (m):     rmse {st.rmse:.6f}  mean {st.mean:.6f}  median {st.median:.6f}  "
        f"std {st.std:.6f}  min {st.min:.6f}  max {st.max:.6f}"
    )
    t, q = r.translation, r.rotation_deg
    click.echo(f"RPE (m, delta {delta}):   rmse {t.rmse:.6f}  mean {t.mean:.6f}  max {t.max:.6f}")
    click.echo(f"RPE (deg, delta {delta}): rmse {q.rmse:.6f}  mean {q.mean:.6f}  max {q.max:.6f}")
