"""`fdi-analyze mso MODEL`: enumerate every MSO set (streaming), with size histogram and fault signatures."""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

from fdi_analysis.model_loader import load_model
from fdi_analysis.mso import find_msos
from fdi_analysis.summary import require_redundancy

EXAMPLE = "example: fdi-analyze mso analysis/models/romo_grouped.toml -o out/grouped --workers 2"


def register(sub: Any) -> None:
    p = sub.add_parser(
        "mso",
        help="count all MSO sets (native engine, multi-core), size histogram, distinct fault signatures",
        description="Enumerate every MSO set of MODEL without storing them; Ctrl-C stops cleanly and reports "
        "the partial count.",
        epilog=EXAMPLE,
    )
    p.add_argument("model", type=Path, help="model file (.toml) or FDT structure (.json)")
    p.add_argument("-o", "--out", type=Path, default=None, help="write mso.json (histogram, signature table)")
    p.add_argument("--workers", type=int, default=2, help="worker processes (default 2)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    model = load_model(args.model)
    st = model.structure()
    require_redundancy(st)
    s = find_msos(st, workers=args.workers, progress=not args.no_progress)
    state = "complete" if s.complete else "INTERRUPTED, partial"
    print(f"{model.name}: {s.count:,} MSO sets ({state}) in {s.elapsed_s:.2f} s on {s.workers} workers, "
          f"{len(s.signatures):,} distinct fault signatures")
    hist = ", ".join(f"{k}:{v:,}" for k, v in sorted(s.by_unknowns.items()))
    print(f"MSO sets by number of unknowns: {hist}")
    if args.out is not None:
        args.out.mkdir(parents=True, exist_ok=True)
        data = {
            "model": model.name,
            "complete": s.complete,
            "count": s.count,
            "elapsed_s": round(s.elapsed_s, 3),
            "workers": s.workers,
            "by_unknowns": {str(k): v for k, v in sorted(s.by_unknowns.items())},
            "signatures": [
                {"faults": [st.faults[k] for k in range(st.nf) if e.faults >> k & 1], "count": e.count,
                 "smallest_unknowns": e.smallest_unknowns,
                 "smallest_equations": [st.equations[k] for k in range(st.ne) if e.smallest >> k & 1]}
                for e in sorted(s.signatures, key=lambda e: (e.smallest_unknowns, e.faults))
            ],
        }
        path = args.out / "mso.json"
        path.write_text(json.dumps(data, indent=1) + "\n", encoding="utf-8")
        print(f"wrote {path}")
    return 0 if s.complete else 130
