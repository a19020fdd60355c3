"""The training report: per imagery, the share of the species' crowns and of each look-alike label that passes
each cue (top-layer SVM, colour, texture, all three), with warnings; report.md and a PNG in one folder.

Windows are the annotated boxes (crown x the model's margin) of the training imageries: the report says what
each cue does on the data the model was trained on, not how well it generalises (that is `foranav evaluate`).
Each imagery is judged with its own colour model and thresholds; an imagery without the species with the
domain the detector would pick for each of its frames (nearest colours).
"""
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from host_tools import fileio
from host_tools.detection import dataset, evaluation
from host_tools.detection.training import Imagery
from host_tools.plotting import plt

import foranav_detector as detector_core
from foranav_model import TreeModel

MAX_WINDOWS = 200  # per imagery and label (seeded sample)
CUES = ("svm", "colour", "texture", "all")
WEAK_POSITIVE_SHARE = 0.5  # a cue passing fewer of an imagery's crowns than this is warned about
COLOUR_ALONE_SHARE = 0.95  # colour rejecting this share of the look-alikes that SVM and texture pass ...
OTHER_CUES_SHARE = 0.1  # ... when at least this share passes them: colour alone rejects them
LOOKALIKE_PASS_SHARE = 0.1


def cue_pass_rates(model: TreeModel, imageries: Sequence[Imagery], seed: int = 0) -> list[dict]:
    """[{imagery, label, n, domain, svm, colour, texture, all}] (shares 0..1), the species first."""
    rng = np.random.RandomState(seed)
    names = [d.name for d in model.domains]
    rows = []
    for imagery in imageries:
        windows = {}
        for frame in imagery.frames:
            own = names.index(imagery.name) if imagery.name in names else evaluation.nearest_domain(model, frame.hsv)
            for box in frame.boxes:
                if not box.label or (box.label == model.species and not frame.complete(box)):
                    continue
                side = dataset.crown_size(box) * model.window_margin
                if side >= 24 and frame.window_fits(box.x_center, box.y_center, side):
                    windows.setdefault(box.label, []).append((frame, own, box.x_center, box.y_center, side))
        labels = sorted(windows, key=lambda label: (label != model.species, label))
        for label in labels:
            items = windows[label]
            if len(items) > MAX_WINDOWS:
                items = [items[i] for i in sorted(rng.choice(len(items), MAX_WINDOWS, replace=False))]
            passed = np.array([_passes_each(model, own, evaluation.frame_window_cues(model, own, f, cx, cy, side))
                               for f, own, cx, cy, side in items])
            used = sorted(set(names[own] for _f, own, _x, _y, _s in items))
            row = {"imagery": imagery.name, "label": label, "target": label == model.species, "n": len(items),
                   "domain": ", ".join(used)}
            row.update((cue, float(passed[:, i].mean())) for i, cue in enumerate(CUES))
            row["svm_texture"] = float((passed[:, 0] & passed[:, 2]).mean())
            rows.append(row)
    return rows


def _passes_each(model: TreeModel, domain_index: int, cues: tuple[float, float, float]) -> list[bool]:
    domain = model.domains[domain_index]
    score, colour, texture = cues
    each = list(detector_core.threshold_tests(score, colour, texture, domain.svm_threshold, domain.hs_threshold,
                                              domain.variance_threshold))
    return each + [all(each)]


def warnings_for(rows: Sequence[dict], imageries: Sequence[Imagery],
                 domain_names: Sequence[str] | None = None) -> list[str]:
    out = []
    for row in rows:
        where = "%s (%s)" % (row["imagery"], row["label"])
        if row["target"]:
            for cue in ("svm", "colour", "texture"):
                if row[cue] < WEAK_POSITIVE_SHARE:
                    out.append("%s rejects %.0f %% of the positives of %s" % (cue, 100 * (1 - row[cue]), row["imagery"]))
            continue
        if (row["svm_texture"] >= OTHER_CUES_SHARE
                and row["all"] <= (1 - COLOUR_ALONE_SHARE) * row["svm_texture"]):
            foreign = row["imagery"] not in [name.strip() for name in row["domain"].split(",")]
            out.append("look-alikes of %s are rejected by colour alone (%.0f %% pass the SVM and texture)%s"
                       % (where, 100 * row["svm_texture"],
                          ": judged with another imagery's colour model, colour may separate the imageries, not the "
                          "species" if foreign else ""))
        if row["all"] > LOOKALIKE_PASS_SHARE:
            out.append("%.0f %% of the look-alikes of %s pass every cue" % (100 * row["all"], where))
    for imagery in imageries:
        if len(imagery.frames) < 3 and (domain_names is None or imagery.name in domain_names):
            out.append("%s has %d frame%s: its thresholds are calibrated on its training frames, not held-back ones"
                       % (imagery.name, len(imagery.frames), "" if len(imagery.frames) == 1 else "s"))
    return out


def write_report(model: TreeModel, imageries: Sequence[Imagery], folder: Path, seed: int = 0) -> dict:
    """Write folder/report.md and folder/cues.png; returns {"path", "warnings", "rows"}."""
    folder = Path(folder)
    rows = cue_pass_rates(model, imageries, seed)
    warnings = warnings_for(rows, imageries, [d.name for d in model.domains])
    lines = ["# Training report: %s" % model.species, "",
             "%s." % model.notes, ""]
    if model.provenance:
        lines += ["Provenance: %s" % model.provenance, ""]
    lines += ["## Thresholds per imagery (colour model: %s)" % model.colour_kind, "",
              "| imagery | SVM | colour | texture |", "|---|---|---|---|"]
    lines += ["| %s | %.3f | %.3f | %.4g |" % (d.name, d.svm_threshold, d.hs_threshold, d.variance_threshold)
              for d in model.domains]
    lines += ["", "Window/crown ratios for whole frames at a given crown size: %s; edge threshold %.2f."
              % (", ".join("%.2f" % r for r in model.crown_ratios), model.edge_threshold), "",
              "## Share of windows passing each cue (training imagery, boxes x margin %.2f)" % model.window_margin, "",
              "| imagery | label | windows | judged with | SVM | colour | texture | all |", "|---|---|---|---|---|---|---|---|"]
    lines += ["| %s | %s%s | %d | %s | %.0f %% | %.0f %% | %.0f %% | %.0f %% |"
              % (r["imagery"], r["label"], " (target)" if r["target"] else "", r["n"], r["domain"], 100 * r["svm"],
                 100 * r["colour"], 100 * r["texture"], 100 * r["all"]) for r in rows]
    lines += ["", "![pass rates](cues.png)", "", "## Warnings", ""]
    lines += ["- %s" % w for w in warnings] or ["none"]
    fileio.write_text(folder / "report.md", "\n".join(lines) + "\n")
    _plot(rows, folder / "cues.png")
    return {"path": str(folder / "report.md"), "warnings": warnings, "rows": rows}


def _plot(rows: Sequence[dict], path: Path) -> None:
    figure, axis = plt.subplots(figsize=(max(6, 0.9 * len(rows) + 2), 4))
    x = np.arange(len(rows))
    for i, cue in enumerate(CUES):
        axis.bar(x + (i - 1.5) * 0.2, [100 * r[cue] for r in rows], 0.2, label=cue)
    axis.set_xticks(x)
    axis.set_xticklabels(["%s\n%s" % (r["imagery"][:18], r["label"]) for r in rows], fontsize=7, rotation=30,
                         ha="right")
    axis.set_ylabel("windows passing, %")
    axis.set_ylim(0, 105)
    axis.legend(fontsize=8)
    axis.set_title("Cue pass rates per imagery and label")
    figure.tight_layout()
    fileio.write_figure(figure, path, dpi=90)
    plt.close(figure)
