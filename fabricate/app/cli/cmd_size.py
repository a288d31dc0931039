"""``fabricate size CONFIG``: the lightest section per beam group that passes the structural check."""
from __future__ import annotations

import sys

from .args import add_config, add_sets, one_value_sets


def register(sub) -> None:
    p = sub.add_parser(
        "size", help="pick the lightest beam section per group that passes the structural check",
        description="Runs the input, optimize and offset stages of CONFIG, then sizes the beams: from the "
                    "candidates in structure.sizing.sections, the lightest section per beam group "
                    "(structure.sizing.group_by) that passes the check (utilization <= 1, deflections within "
                    "their limits) by a full OpenSees solve; reports the steel saved against the configured "
                    "section (structure.section, or the section the parts are welded from: parts.beam).",
        epilog="Exit codes: 0 a passing choice, 2 bad input, 3 no candidate passes (the heaviest is reported).")
    add_config(p, "YAML run configuration with structure.sizing.sections")
    add_sets(p, "override a config value, e.g. --set structure.loads.snow=1.2 (repeatable)")
    p.add_argument("--json", metavar="FILE", help="also write the sizing as JSON (atomic)")
    p.set_defaults(handler=run)


def run(args) -> int:
    import json
    from pathlib import Path

    from fabricate.app import stages
    from fabricate.app.config import load_config
    from fabricate.structure.sizing import size_sections
    from optimize.atomic import atomic_open
    from optimize.errors import ConfigError

    cfg = load_config(args.config, overrides=one_value_sets(args.sets, "size"))
    if not cfg.structure.sizing.sections:
        raise ConfigError(f"{cfg.source}: structure.sizing.sections: empty, expected a list of candidate sections "
                          "(e.g. - {shape: rhs, depth: 200, width: 100, web: 6})")
    off = stages.stage_offset(cfg, stages.stage_optimize(cfg, stages.stage_input(cfg)))
    sz = size_sections(off.structure, cfg.structure.to_options(), stages.part_spec(cfg))
    d = sz.as_dict()
    print(f"{cfg.name}: sizing {sum(d['beams'].values())} beams ({cfg.structure.grade}, "
          f"{len(cfg.structure.sizing.sections)} candidates, group_by {cfg.structure.sizing.group_by})")
    print(f"  {'group':<10} {'beams':>6}  {'section':<24} {'max utilization':>15}")
    for g, name in d["chosen"].items():
        print(f"  {g:<10} {d['beams'][g]:>6}  {name:<24} {d['max_utilization'][g]:>15.3f}")
    r = sz.check.results
    print(f"  beam deflection {float((r.deflection_mm / r.deflection_limit_mm).max()):.3f} of "
          f"L/{cfg.structure.deflection_limit:g}; node displacement {float(r.displacement_mm.max()):.1f} mm of "
          f"{r.displacement_limit_mm:.0f} mm")
    print(f"  steel: {d['configured_mass_kg'] / 1000:.1f} t with {d['configured_section']} -> "
          f"{d['sized_mass_kg'] / 1000:.1f} t sized: {d['saved_kg'] / 1000:.1f} t saved ({d['saved_percent']:.1f}%)")
    if args.json:
        with atomic_open(Path(args.json)) as fh:
            fh.write(json.dumps(d, indent=2) + "\n")
    if not sz.passes:
        print(f"warning: {cfg.name}: no candidate section passes for every group (max utilization "
              f"{sz.check.max_utilization:.3g}); add heavier candidates", file=sys.stderr)
        return 3
    return 0
