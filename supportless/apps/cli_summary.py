"""What a command prints of a result: the support headline, the rest pose against the answer, the answers weighed.

Used by ``optimize`` (:mod:`supportless.apps.cli_optimize`) and ``demo``
(:mod:`supportless.apps.cli_demo`); the figures come from the report
(:func:`supportless.report.report.build_report`).
"""

from __future__ import annotations

__all__ = ["strength_rows"]


def _standing_word(before: dict, after: dict) -> str:
    """How the found pose stands, said against the rest pose."""
    if after["stands"]:
        return "stands"
    if not before["stands"] and after.get("as_steady_as_rest"):
        return "does not stand, nor does the rest pose (no worse)"
    return "FALLS OVER" if after["stability_margin"] < 0 else "touches the plate anew"


def _summary_table(report: dict, verbose: bool = False):
    """The rest pose against the found pose; the support estimates only when ``verbose``.

    Volumes and areas are shown in the print frame's millimetres (the report
    keeps them in the model's units).
    """
    from rich.table import Table

    b, a, red = report["before"], report["after"], report["reduction_percent"]
    scale = (report.get("print_frame") or {}).get("scale", 1.0)

    def pct(x):  # a reduction of 40 % shows as -40.0 %
        return "-" if x is None else f"{-x:+.1f} %"

    def cm3(x):  # a volume of the model's units^3, in cm3 as printed
        return f"{x * scale ** 3 / 1000:,.2f} cm3"

    def mm3(x):
        return f"{x * scale ** 3:,.1f} mm3"

    table = Table(title=f"{report['model']}: rest pose vs found pose")
    for col in ("measure", "before", "after", "change"):
        table.add_column(col, justify="right" if col != "measure" else "left")
    if verbose:
        predicted = report.get("predicted_slicer")
        if predicted:
            fraction = predicted["reduction"]
            table.add_row(f"estimate: PrusaSlicer's support filament ({predicted['height_mm']:g} mm tall)",
                          f"{predicted['before_mm']:,.0f} mm", f"{predicted['after_mm']:,.0f} mm",
                          pct(None if fraction is None else 100 * fraction))
        table.add_row("estimate: support volume (prisms)", cm3(b["support_prism"]), cm3(a["support_prism"]),
                      pct(red["support_prism"]))
        table.add_row("estimate: support volume (columns)", cm3(b["support_column"]), cm3(a["support_column"]),
                      pct(red["support_column"]))
        table.add_row("area needing support", f"{b['risky_area'] * scale ** 2:,.0f} mm2",
                      f"{a['risky_area'] * scale ** 2:,.0f} mm2", pct(red["risky_area"]))
    table.add_row("distortion (ARAP / volume)", f"{b['terms']['arap']:.3f}", f"{a['terms']['arap']:.3f}", "")
    table.add_row("self-intersection volume", mm3(b["self_intersection_volume"]),
                  mm3(a["self_intersection_volume"]), "")

    def pairs(x):
        return "n/a (2D)" if x is None or x < 0 else str(x)

    table.add_row("intersecting face pairs (exact)", pairs(b.get("intersecting_face_pairs")),
                  pairs(a.get("intersecting_face_pairs")), "contact: one solid as written" if report.get("contacts") else "")
    table.add_row("new contacts with the plate", str(b["new_contact_vertices"]), str(a["new_contact_vertices"]), "")
    table.add_row("stability margin (of the height)", f"{100 * b['stability_margin']:.1f} %",
                  f"{100 * a['stability_margin']:.1f} %", _standing_word(b, a))
    table.add_row("largest joint rotation", "0°", f"{report['largest_rotation_deg']:.0f}°", "")
    natural = report.get("naturalness") or {}
    if natural.get("largest_chain_turn_deg") is not None:
        end = natural.get("chain_end_name") or f"bone {natural['chain_end']}"
        table.add_row("largest turn of a chain's end", "0°", f"{natural['largest_chain_turn_deg']:.0f}°", end)
    sym = report.get("symmetry")
    if sym:
        table.add_row("left and right", "", sym["kept"], "the rest skeleton has a mirror plane")
    use = natural.get("joint_range")
    if use:
        table.add_row("named joint nearest its range", "", f"{use['angle_deg']:.0f}° of {use['limit_deg']:.0f}°",
                      f"{use['joint']} ({use['measure']})"
                      + (f", {use['outside_deg']:.0f}° outside" if use["outside_deg"] >= 0.5 else ""))
    for row in strength_rows(report):
        table.add_row(*row)
    rot = report.get("print_rotation")
    if rot and rot["angle_deg"] >= 0.5:  # a turn that shows in whole degrees
        up = report["up"]
        table.add_row("printed turned by", "0°", f"{rot['angle_deg']:.0f}°",
                      f"model {[round(x, 2) for x in rot['printing_direction_in_model_frame']]} up, was {up}")
        if report.get("footprint"):  # the first layer's contact (a turn rests on at least the bound)
            fp = report["footprint"]
            table.add_row("first layer on the plate", f"{fp['rest_mm2']:.0f} mm²", f"{fp['answer_mm2']:.0f} mm²",
                          f"a turn rests on ≥ {fp['bound_mm2']:g} mm²")
        if verbose:
            table.add_row("estimate: support standing (prisms)", cm3(b["support_prism"]),
                          cm3(a["upright"]["support_prism"]),
                          pct(None if b["support_prism"] <= 0 else
                              100 * (1 - a["upright"]["support_prism"] / b["support_prism"])))
    return table


def _print_results(console, report, verbose=False):
    """The one support figure, the before/after table and the search time."""
    headline = report.get("support")
    if headline:
        console.print(headline["line"])
    console.print(_summary_table(report, verbose))
    console.print(_contact_line(report))
    console.print(f"search took {report['runtime_seconds']:.1f} s")


def _contact_line(report: dict) -> str:
    """Lines: the best answer printed standing beside the answer (when it is another), the skinning that posed
    the answer, and its contacts merged as written."""
    contacts = report.get("contacts") or []
    line = ""
    standing = report.get("standing")
    if standing and not standing["is_answer"] and standing["answer_turned_deg"] >= 1.0:  # the answer is turned
        line = (f"standing as displayed: {standing['standing_g']:.1f} g of support ({standing['source']}); the "
                f"answer, turned {standing['answer_turned_deg']:.0f}° to print: {standing['answer_g']:.1f} g "
                "(--standing-out writes the standing one)\n")
    line += f"posed by {report.get('skinning', 'linear blend skinning')}"
    between = sorted((c for c in contacts if c["parts"][0] != c["parts"][1]), key=lambda c: -c["pairs"])
    if contacts:
        named = [f"{c['parts'][0].split(':')[-1]} with {c['parts'][1].split(':')[-1]}" for c in between[:4]]
        more = len(between) - len(named)
        where = (", ".join(named) + (f" and {more} more" if more > 0 else "") if named  # else one part folds on itself
                 else f"{contacts[0]['parts'][0].split(':')[-1]} against itself")
        line += f"; {contacts[0]['overlap_mm3']:,.0f} mm³ of contact merged into one solid as written ({where})"
    return line


def strength_rows(report: dict) -> list[tuple[str, str, str, str]]:
    """The summary table's strength row: the safety factors of the rest pose and the answer, and the answer's
    weakest section in a line (:func:`~supportless.report.report.strength_line`)."""
    from ..report.report import strength_line

    s = report.get("strength")
    if not s:
        return []

    def factor(part):
        return "never pulled" if s[part]["safety_factor"] is None else f"{s[part]['safety_factor']:.2f}"

    return [(f"safety factor ({s['material']['name']}, {s['load_n']:g} N grip)", factor("rest"), factor("answer"),
             strength_line(s) or "")]


def _print_choice(console, choice, slicer_tried, label="PrusaSlicer"):
    """One line per answer weighed, and who chose."""
    from ..search.choice import REST_STRENGTH_TOLERANCE

    for i, c in enumerate(choice.candidates):
        sliced = "" if c.sliced_mm is None else f", {label} {c.sliced_mm:.0f} mm"
        mark = ("  <- chosen" if i == choice.chosen else "") + \
            ("" if c.same_as is None else f"  (prints as answer {c.same_as + 1})")
        console.print(f"  {i + 1}. {c.kind:<13} predicted {c.predicted_mm:6.0f} mm{sliced}{mark}")
    who = label if choice.by == "slicer" else "the slicer model" + \
        ("" if slicer_tried else f" ({label} not found or not asked for: nothing sliced)")
    console.print(f"  chosen by {who}: {choice.reason}")
    refused = (choice.strength or {}).get("refused") or []
    if refused:
        console.print(f"  left out as weaker than the rest pose (safety {choice.strength['rest_safety_factor']}, "
                      f"less {100 * REST_STRENGTH_TOLERANCE:g} %) and "
                      f"{choice.strength['floor']:g}: " + ", ".join(
                          f"{r['kind']} {r['predicted_mm']:.0f} mm (safety {r['safety_factor']})" for r in refused))
