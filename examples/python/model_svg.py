"""Draws a planar model at its initial poses (as written in the file) as an SVG.

    python3 examples/python/model_svg.py examples/breaker_linkage.yaml docs/breaker_linkage.svg

Each rigid body is drawn as the polygon through its markers (a line for a two-marker link), each
ground marker used by a revolute joint as a frame pivot, each translational joint as a dashed
guide line along its axis, and each revolute joint is labelled with its name (clearance joints in
red). It needs only PyYAML; the model is read as written, not assembled, so the file's poses must
already close the joints (they do for examples/breaker_linkage.yaml to 1e-6 m).
"""
import math
import sys

import yaml


def world(body, marker, bodies, ground):
    if body == "ground":
        return tuple(ground[marker]) if marker else (0.0, 0.0)
    b = bodies[body]
    x, y = b.get("position", [0, 0])
    a = b.get("angle", math.radians(b.get("angle_deg", 0)))
    mx, my = b.get("markers", {}).get(marker, [0, 0]) if marker else (0, 0)
    return (x + math.cos(a) * mx - math.sin(a) * my, y + math.sin(a) * mx + math.cos(a) * my)


def point(ref, bodies, ground):
    body, _, marker = ref.partition(".")
    return world(body, marker, bodies, ground)


def main(model_file, svg_file):
    m = yaml.safe_load(open(model_file))
    bodies, ground = m["bodies"], m.get("ground", {}).get("markers", {})
    defaults = m.get("clearance_defaults", {})
    pts = [world(n, k, bodies, ground) for n, b in bodies.items() for k in b.get("markers", {})]
    pts += [tuple(p) for p in ground.values()]
    # Guide lines: 0.6 m along each translational joint's axis, centred where its slider sits.
    guides = []
    for name, j in m["joints"].items():
        if j["type"] == "translational":
            g, sl = point(j["guide"], bodies, ground), point(j["slider"], bodies, ground)
            ax = j.get("axis", [1, 0])
            n = math.hypot(*ax)
            u = (ax[0] / n, ax[1] / n)
            along = (sl[0] - g[0]) * u[0] + (sl[1] - g[1]) * u[1]
            c = (g[0] + along * u[0], g[1] + along * u[1])
            guides.append((name, (c[0] - 0.3 * u[0], c[1] - 0.3 * u[1]), (c[0] + 0.3 * u[0], c[1] + 0.3 * u[1])))
            pts += [guides[-1][1], guides[-1][2]]
    x0, x1 = min(p[0] for p in pts) - 0.15, max(p[0] for p in pts) + 0.15
    if x1 - x0 < 1.0:  # room for the labels
        x0, x1 = (x0 + x1) / 2 - 0.5, (x0 + x1) / 2 + 0.5
    y0, y1 = min(p[1] for p in pts) - 0.15, max(p[1] for p in pts) + 0.15
    s = 400.0  # pixels per metre
    X = lambda p: (p[0] - x0) * s
    Y = lambda p: (y1 - p[1]) * s
    out = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{(x1 - x0) * s:.0f}" height="{(y1 - y0) * s:.0f}" '
           f'font-family="sans-serif" font-size="13">',
           f'<title>{m.get("name", "model")} at t = 0 (drawn from {model_file})</title>',
           '<rect width="100%" height="100%" fill="white"/>']
    for name, a, b in guides:  # guide lines first, under the bodies
        out.append(f'<line x1="{X(a):.1f}" y1="{Y(a):.1f}" x2="{X(b):.1f}" y2="{Y(b):.1f}" '
                   'stroke="#999" stroke-dasharray="6 4"/>')
        out.append(f'<text x="{X(b) + 4:.1f}" y="{Y(b) - 4:.1f}" fill="#777">{name}</text>')
    for i, (name, b) in enumerate(bodies.items()):
        ms = [world(name, k, bodies, ground) for k in b.get("markers", {})]
        if len(ms) >= 2:
            poly = " ".join(f"{X(p):.1f},{Y(p):.1f}" for p in ms)
            out.append(f'<polyline points="{poly}{" " + f"{X(ms[0]):.1f},{Y(ms[0]):.1f}" if len(ms) > 2 else ""}" '
                       'fill="none" stroke="#2b5d9b" stroke-width="7" stroke-linejoin="round" stroke-opacity="0.8"/>')
        c = world(name, None, bodies, ground)
        out.append(f'<circle cx="{X(c):.1f}" cy="{Y(c):.1f}" r="3" fill="black"/>')
        out.append(f'<text x="{X(c) + 8:.1f}" y="{Y(c) + 16:.1f}" fill="#2b5d9b">{i + 1} {name}</text>')
    for name, j in m["joints"].items():
        if j["type"] != "revolute":
            continue
        p = point(j["journal"], bodies, ground)
        clearance = j.get("clearance", 0) > 0 or "bearing_radius" in j
        colour = "#c0392b" if clearance else "black"
        if j["bearing"].startswith("ground") or j["journal"].startswith("ground"):
            out.append(f'<path d="M {X(p):.1f} {Y(p):.1f} l -10 18 h 20 z" fill="#ccc" stroke="black"/>')
        out.append(f'<circle cx="{X(p):.1f}" cy="{Y(p):.1f}" r="6" fill="white" stroke="{colour}" stroke-width="2"/>')
        label = name + (f" (c = {j['clearance'] * 1e3:g} mm)" if clearance and "clearance" in j else "")
        out.append(f'<text x="{X(p) - 12:.1f}" y="{Y(p) - 10:.1f}" fill="{colour}" font-weight="bold">{label}</text>')
    out.append(f'<text x="10" y="{(y1 - y0) * s - 10:.0f}" fill="#555">{m.get("name", "")} at t = 0; '
               f'grid-free, 1 m = {s:.0f} px; gravity {m.get("gravity", [0, 0])} m/s²</text>')
    out.append("</svg>")
    open(svg_file, "w").write("\n".join(out) + "\n")


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2])
