"""The fleet on a map and on a page: the map (PNG; GeoJSON and KML through the run
exporter's track writers, `sim.export`), and the fleet page of the offline HTML report
(the report's own page machinery, `reports.html`).

Everything is drawn from the plan's report (fleet.json) and, when given, what the
simulator flew (`fleet sim`'s tracks) and what the Monte Carlo found.
"""

from __future__ import annotations

import json
import math
import xml.etree.ElementTree as ET

import numpy as np

from gliderplan.language.fleet import Fleet
from gliderplan.reports.figures import pyplot, render

COLOURS = ("#1b6ca8", "#d1495b", "#2a9d8f", "#e9a23b", "#6a4c93", "#8d6e63", "#00798c",
           "#c1666b", "#4d908e", "#f4a261")
KML_NS = "http://www.opengis.net/kml/2.2"


def colour(n: int) -> str:
    return COLOURS[n % len(COLOURS)]


def _lonlat(fleet: Fleet, points) -> np.ndarray:
    points = np.asarray(points, float).reshape(-1, 2)
    lat, lon = fleet.projection.to_latlon(points[:, 0], points[:, 1])
    return np.column_stack([lon, lat])


# ---- the map -----------------------------------------------------------------------------

def map_figure(fleet: Fleet, report: dict, plan=None, flown: dict | None = None):
    """The survey, each glider's lines, planned track and start; what it flew (dashed)
    when `flown` (glider -> rows of lon, lat, time) is given; beside it the time-averaged
    mapping error of the plan when `plan` (a FleetPlan) is given."""
    plt = pyplot()
    panels = 2 if plan is not None else 1
    fig, axes = plt.subplots(1, panels, figsize=(6.2 * panels, 5.6), squeeze=False)
    ax = axes[0][0]
    for area in fleet.areas:
        ring = _lonlat(fleet, [*area, area[0]])
        ax.fill(ring[:, 0], ring[:, 1], color="#eef2f5", zorder=0)
        ax.plot(ring[:, 0], ring[:, 1], color="#9aa5b1", lw=0.8, zorder=1)
    for keepout in fleet.keepouts:
        ring = _lonlat(fleet, [*keepout, keepout[0]])
        ax.fill(ring[:, 0], ring[:, 1], facecolor="none", edgecolor="#b00020", hatch="///",
                lw=0.8, zorder=2, label=None)
    owner = {p: n for n, g in enumerate(report["gliders"]) for p in g["parts"]}
    for part in fleet.parts:
        ends = _lonlat(fleet, [part.a, part.b])
        ax.plot(ends[:, 0], ends[:, 1], color=colour(owner.get(part.index, 0)), lw=3.2,
                alpha=0.45, solid_capstyle="butt", zorder=3)
    for n, glider in enumerate(report["gliders"]):
        path = _lonlat(fleet, glider["track"]["points_m"])
        ax.plot(path[:, 0], path[:, 1], color=colour(n), lw=0.9, zorder=4,
                label=f"{glider['name']} ({len(glider['parts'])} line"
                      f"{'s' if len(glider['parts']) != 1 else ''})")
        ax.plot(path[0, 0], path[0, 1], marker="^", color=colour(n), ms=7, zorder=6)
        if flown and glider["name"] in flown:
            track = flown[glider["name"]]
            ax.plot(track[:, 0], track[:, 1], color=colour(n), lw=0.9, ls="--", zorder=5)
            ax.plot(track[-1, 0], track[-1, 1], marker="x", color=colour(n), ms=7, zorder=6)
    _degrees(ax, fleet)
    ax.set_title(f"{fleet.name}: lines and tracks" + (" (dashed: flown)" if flown else ""),
                 fontsize=10)
    ax.legend(fontsize=7, loc="best")
    if plan is not None:
        ax2 = axes[0][1]
        mean = plan.evaluation.errors.mean(axis=0)
        lonlat = _lonlat(fleet, np.column_stack([plan.grid.x, plan.grid.y]))
        shown = ax2.scatter(lonlat[:, 0], lonlat[:, 1], c=mean, cmap="viridis_r", vmin=0.0,
                            vmax=1.0, s=14, marker="s", linewidths=0)
        fig.colorbar(shown, ax=ax2, shrink=0.8, label="mapping error (share of variance)")
        _degrees(ax2, fleet)
        ax2.set_title(f"mapping error over the period: mean {report['mapping_error']:.3f} "
                      f"(equal split {report['baseline_mapping_error']:.3f})", fontsize=10)
    fig.tight_layout()
    return fig


def _degrees(ax, fleet: Fleet) -> None:
    ax.set_xlabel("longitude [deg]")
    ax.set_ylabel("latitude [deg]")
    ax.set_aspect(1.0 / math.cos(math.radians(fleet.projection.lat0)))
    ax.grid(True, lw=0.3, alpha=0.5)


def map_png(fleet: Fleet, report: dict, plan=None, flown=None) -> bytes:
    return render(map_figure(fleet, report, plan, flown), "png")


def _track_table(fleet: Fleet, glider: dict, flown: np.ndarray | None = None):
    """A glider's track as the run exporter's table (time_s, lat_deg, lon_deg); `flown`:
    (lon, lat, time [s after its start]) rows of what it flew."""
    import pandas as pd

    from gliderplan.planner.fleet_report import track_from_json

    if flown is not None:
        return pd.DataFrame({"time_s": flown[:, 2], "lat_deg": flown[:, 1],
                             "lon_deg": flown[:, 0]})
    track = track_from_json(glider["track"])
    lonlat = _lonlat(fleet, track.points)
    return pd.DataFrame({"time_s": track.time_at(track.distance_m), "lat_deg": lonlat[:, 1],
                         "lon_deg": lonlat[:, 0]})


def _meta(fleet: Fleet, glider: dict, what: str) -> dict:
    from gliderplan.sim.export import utc_text

    return {"mission": f"{glider['name']} {what}",
            "start_utc": utc_text(fleet.start_epoch_s + glider["track"]["start_offset_s"])}


def geojson(fleet: Fleet, report: dict, flown: dict | None = None) -> str:
    """The survey (areas, keep-outs), each glider's lines and its planned track (and
    flown track), as one GeoJSON FeatureCollection."""
    from gliderplan.sim.export import track_geojson

    features = []
    for kind, rings in (("area", fleet.areas), ("keepout", fleet.keepouts)):
        for ring in rings:
            coords = _lonlat(fleet, [*ring, ring[0]]).round(7).tolist()
            features.append({"type": "Feature", "geometry": {"type": "Polygon",
                                                             "coordinates": [coords]},
                             "properties": {"name": kind, "kind": kind}})
    for n, glider in enumerate(report["gliders"]):
        lines = [_lonlat(fleet, [fleet.parts[p].a, fleet.parts[p].b]).round(7).tolist()
                 for p in glider["parts"]]
        features.append({"type": "Feature",
                         "geometry": {"type": "MultiLineString", "coordinates": lines},
                         "properties": {"name": f"{glider['name']} lines", "kind": "assignment",
                                        "glider": glider["name"], "parts": glider["parts"],
                                        "stroke": colour(n)}})
        tracks = [("planned", None)]
        if flown and glider["name"] in flown:
            tracks.append(("flown", flown[glider["name"]]))
        for what, points in tracks:
            doc = json.loads(track_geojson(_track_table(fleet, glider, points),
                                           _meta(fleet, glider, what)))
            for feature in doc["features"]:
                feature["properties"].update(glider=glider["name"], kind=f"{what} track",
                                             stroke=colour(n))
                features.append(feature)
    return json.dumps({"type": "FeatureCollection", "name": fleet.name,
                       "features": features}, indent=1) + "\n"


def kml(fleet: Fleet, report: dict, flown: dict | None = None) -> str:
    """The same as KML 2.2: the survey, the lines, and each track's placemarks as the run
    exporter writes them."""
    from gliderplan.sim.export import track_kml

    ET.register_namespace("", KML_NS)
    root = ET.Element(f"{{{KML_NS}}}kml")
    document = ET.SubElement(root, f"{{{KML_NS}}}Document")
    ET.SubElement(document, f"{{{KML_NS}}}name").text = fleet.name

    def placemark(name: str, geometry: ET.Element) -> None:
        mark = ET.SubElement(document, f"{{{KML_NS}}}Placemark")
        ET.SubElement(mark, f"{{{KML_NS}}}name").text = name
        mark.append(geometry)

    def coordinates(points: np.ndarray) -> str:
        return " ".join(f"{x:.7f},{y:.7f},0" for x, y in points)

    for kind, rings in (("area", fleet.areas), ("keepout", fleet.keepouts)):
        for ring in rings:
            polygon = ET.Element(f"{{{KML_NS}}}Polygon")
            outer = ET.SubElement(ET.SubElement(polygon, f"{{{KML_NS}}}outerBoundaryIs"),
                                  f"{{{KML_NS}}}LinearRing")
            ET.SubElement(outer, f"{{{KML_NS}}}coordinates").text = coordinates(
                _lonlat(fleet, [*ring, ring[0]]))
            placemark(kind, polygon)
    for glider in report["gliders"]:
        multi = ET.Element(f"{{{KML_NS}}}MultiGeometry")
        for p in glider["parts"]:
            line = ET.SubElement(multi, f"{{{KML_NS}}}LineString")
            ET.SubElement(line, f"{{{KML_NS}}}coordinates").text = coordinates(
                _lonlat(fleet, [fleet.parts[p].a, fleet.parts[p].b]))
        placemark(f"{glider['name']} lines", multi)
        tracks = [("planned", None)]
        if flown and glider["name"] in flown:
            tracks.append(("flown", flown[glider["name"]]))
        for what, points in tracks:
            text = track_kml(_track_table(fleet, glider, points), _meta(fleet, glider, what))
            for child in ET.fromstring(text).find(f"{{{KML_NS}}}Document"):
                if child.tag == f"{{{KML_NS}}}Placemark":
                    document.append(child)
                elif child.tag == f"{{{KML_NS}}}Style" and document.find(child.tag) is None:
                    document.insert(1, child)  # styles before the features, once
    ET.indent(root)
    return '<?xml version="1.0" encoding="UTF-8"?>\n' + ET.tostring(root, "unicode") + "\n"


def map_files(fleet: Fleet, report: dict, plan=None, flown=None) -> dict[str, str | bytes]:
    return {"fleet.png": map_png(fleet, report, plan, flown),
            "fleet.geojson": geojson(fleet, report, flown),
            "fleet.kml": kml(fleet, report, flown)}


# ---- the page ----------------------------------------------------------------------------

def page(fleet: Fleet, report: dict, *, plan=None, flown: dict | None = None,
         sim: dict | None = None, montecarlo: dict | None = None,
         png: bytes | None = None) -> str:
    """The fleet page: the plan against the equal split, the gliders, the map, and what
    the simulator (`sim`: fleet_sim.json) and the Monte Carlo (`montecarlo`:
    summary.json) found."""
    import pandas as pd

    from gliderplan.contract.units import J_PER_WH
    from gliderplan.planner.fleet_capacity import hours
    from gliderplan.reports.html import Section, Table, esc, facts_html
    from gliderplan.reports.html import page as html_page

    facts = [
        ("mapping error", f"{report['mapping_error']:.3f} (equal split "
                          f"{report['baseline_mapping_error']:.3f}: "
                          f"{100 * report['improvement']:.1f} % lower)"),
        ("finish (every line swept)", f"{esc(report['finish_time_utc'])}, in "
                                      f"{report['validation']['finished']} of "
                                      f"{report['validation']['scenarios']} scenarios "
                                      f"(at least {100 * report['confidence_lower_bound']:.1f} "
                                      f"%; asked {100 * report['confidence']:.0f} %)"),
        ("survey", f"{esc(report['start_utc'])} to {esc(report['finish_by_utc'])}, "
                   f"{len(report['lines'])} lines, {len(report['gliders'])} gliders"),
        ("assignment", f"{esc(report['assignment']['method'])} "
                       f"({esc(report['assignment']['status'])})"),
        ("field", f"length {report['field']['length_m'] / 1000:g} km, time "
                  f"{hours(report['field']['time_s'])}, noise {report['field']['noise']:g}"),
    ]
    if report["why_not"]:
        facts.append(("why not 20 %", esc(report["why_not"])))
    sections = [Section("fleet-summary", "Fleet plan", (facts_html(facts),),
                        notes=(report["field"]["source"], *report["notes"]))]
    rows = [{"glider": g["name"], "vehicle": g["vehicle"], "computer": g["computer"],
             "lines": len(g["parts"]), "speed": g["speed_mps"], "until_d": g["end_s"] / 86400,
             "energy_wh": g["energy_j"] / J_PER_WH, "budget_wh": g["budget_j"] / J_PER_WH,
             "margin": g["margin_j"] / max(g["budget_j"], 1.0),
             "first_sweep_h": g["first_coverage_s"] / 3600,
             "per_kwh": g["shadow_price_per_kwh"]} for g in report["gliders"]]
    sections.append(Section(
        "fleet-gliders", "Gliders",
        ("<p>Each glider flies one block of lines back and forth until the survey ends "
         "or its battery does. 'per kWh': mapping error lowered by one more kWh of its "
         "battery (0: its battery does not limit the survey).</p>",),
        tables=(Table(pd.DataFrame(rows), headers={
            "speed": "speed [m/s]", "until_d": "flies until [d]", "energy_wh": "energy [Wh]",
            "budget_wh": "budget [Wh]", "margin": "margin [1]",
            "first_sweep_h": "first sweep [h]", "per_kwh": "per kWh"},
            formats={"speed": ".3f", "until_d": ".2f", "energy_wh": ",.0f",
                     "budget_wh": ",.0f", "margin": ".0%", "first_sweep_h": ".1f",
                     "per_kwh": ".3g"}),)))
    import base64

    picture = png if png is not None else map_png(fleet, report, plan, flown)
    sections.append(Section("fleet-map", "Map", (
        '<figure data-figure="fleet-map"><img style="max-width:100%" alt="the fleet map" '
        f'src="data:image/png;base64,{base64.b64encode(picture).decode()}">'
        "<figcaption>Lines by glider (thick), planned tracks (thin), starts (triangles)"
        + (", flown tracks (dashed; x where each ended)" if flown else "")
        + '; keep-out areas hatched. Data: <a href="fleet.geojson">fleet.geojson</a>, '
        '<a href="fleet.kml">fleet.kml</a>.</figcaption></figure>',)))
    if sim is not None:
        rows = [{"glider": g["name"], "energy_wh": g["energy_j"] / J_PER_WH,
                 "budget_wh": g["budget_j"] / J_PER_WH, "ended": g["ended"],
                 "swept": g["swept"], "lines": g["lines_swept"]} for g in sim["gliders"]]
        paras = [f"<p>Flown once in the simulator: the survey "
                 f"{'was' if sim['finished'] else 'was not'} finished; realised mapping "
                 f"error {sim['mapping_error']:.3f} (planned {report['mapping_error']:.3f}).</p>"]
        if sim.get("lost"):
            lost = sim["lost"]
            paras.append(f"<p>{esc(lost['glider'])} lost {esc(hours(lost['at_s']))} in: "
                         f"{esc(lost['summary'])}</p>")
        sections.append(Section("fleet-sim", "Simulated flight", tuple(paras), tables=(
            Table(pd.DataFrame(rows), headers={"energy_wh": "energy [Wh]",
                                               "budget_wh": "budget [Wh]",
                                               "swept": "block swept", "lines": "lines swept"},
                  formats={"energy_wh": ",.0f", "budget_wh": ",.0f"}),)))
    if montecarlo is not None:
        rows = [{"glider": name, **{k: v / J_PER_WH for k, v in q.items()}}
                for name, q in montecarlo["energy_j"].items()]
        if montecarlo["finish_probability"] is None:  # interrupted: no finish probability
            finish = (f"Interrupted after {montecarlo['scenarios']} of "
                      f"{montecarlo['requested']} scenarios: a partial run gives no finish "
                      "probability (those that finished are not the sample asked for).")
        else:
            low, high = montecarlo["finish_interval"]
            finish = (f"The survey finished in {montecarlo['finished']} of "
                      f"{montecarlo['scenarios']} scenarios: "
                      f"{100 * montecarlo['finish_probability']:.1f} % (95 % interval "
                      f"{100 * low:.1f}-{100 * high:.1f} %), against the planned "
                      f"{100 * report['confidence']:.0f} %.")
        sections.append(Section(
            "fleet-montecarlo", "Monte Carlo",
            (f"<p>{finish} Realised mapping error "
             f"{montecarlo['mapping_error']['p50']:.3f} (median; 5-95 % "
             f"{montecarlo['mapping_error']['p05']:.3f}-"
             f"{montecarlo['mapping_error']['p95']:.3f}).</p>",),
            tables=(Table(pd.DataFrame(rows), headers={"p05": "energy 5 % [Wh]",
                                                       "p50": "50 % [Wh]", "p95": "95 % [Wh]"},
                          formats={"p05": ",.0f", "p50": ",.0f", "p95": ",.0f"}),)))
    return html_page(f"gliderplan fleet: {fleet.name}",
                     f"{fleet.filename}, planned with seed {report['seed']}", sections)
