#!/usr/bin/env python3
"""Damping ratio against frequency as SVG (standard library only): the partials of one or more
`chladni estimate --json` outputs with their 1-sigma bars, and each file's fitted damping curve,
zeta(f) = beta(omega^2) / (2 omega).
Usage: scripts/plot_damping.py OUT.svg TITLE FILE.json[=LABEL] ..."""
import json
import math
import sys

W, H, L, R, T, B = 720, 440, 70, 20, 40, 50
F0, F1, Z0, Z1 = 100.0, 20000.0, 1e-5, 1e-1
COLOURS = ["#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b"]


def beta(model, x):
    kind, _, params = model.partition(":")
    a = [float(v) for v in params.split(",")]
    if kind == "rayleigh":
        return a[0] + a[1] * x
    if kind == "caughey":
        return sum(c * x**j for j, c in enumerate(a))
    if kind == "power":
        return a[0] * x ** a[1]
    return a[0] + a[1] * x + a[2] * x ** a[3]  # hybrid


def px(f):
    return L + (W - L - R) * math.log(f / F0) / math.log(F1 / F0)


def py(z):
    z = min(max(z, Z0), Z1)
    return T + (H - T - B) * (1 - math.log(z / Z0) / math.log(Z1 / Z0))


def main():
    out, title, files = sys.argv[1], sys.argv[2], sys.argv[3:]
    s = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{H}" '
         f'font-family="sans-serif" font-size="12">',
         f'<rect width="{W}" height="{H}" fill="white"/>',
         f'<text x="{W / 2}" y="20" text-anchor="middle" font-size="14">{title}</text>']
    for f in [100, 200, 500, 1000, 2000, 5000, 10000, 20000]:
        s.append(f'<line x1="{px(f):.1f}" y1="{T}" x2="{px(f):.1f}" y2="{H - B}" stroke="#ddd"/>')
        s.append(f'<text x="{px(f):.1f}" y="{H - B + 16}" text-anchor="middle">'
                 f'{f / 1000:g}k</text>' if f >= 1000 else
                 f'<text x="{px(f):.1f}" y="{H - B + 16}" text-anchor="middle">{f}</text>')
    for e in range(-5, 0):
        z = 10.0**e
        s.append(f'<line x1="{L}" y1="{py(z):.1f}" x2="{W - R}" y2="{py(z):.1f}" stroke="#ddd"/>')
        s.append(f'<text x="{L - 6}" y="{py(z) + 4:.1f}" text-anchor="end">1e{e}</text>')
    s.append(f'<text x="{(L + W - R) / 2}" y="{H - 12}" text-anchor="middle">frequency (Hz)</text>')
    s.append(f'<text transform="translate(16,{(T + H - B) / 2}) rotate(-90)" '
             f'text-anchor="middle">damping ratio d / omega</text>')
    for i, spec in enumerate(files):
        path, _, label = spec.partition("=")
        j = json.load(open(path))
        c = COLOURS[i % len(COLOURS)]
        model = j["damping_curve"]["model"]
        label = label or path
        pts = []
        for k in range(201):
            f = F0 * (F1 / F0) ** (k / 200)
            w = 2 * math.pi * f
            z = beta(model, w * w) / (2 * w)
            if z > 0:
                pts.append(f"{px(f):.1f},{py(z):.1f}")
        s.append(f'<polyline points="{" ".join(pts)}" fill="none" stroke="{c}" stroke-width="2"/>')
        for r in j["recordings"]:
            for p in r["features"]:
                f, w = p["frequency_hz"], 2 * math.pi * p["frequency_hz"]
                if not F0 <= f <= F1:
                    continue
                z, dz = p["decay_per_s"] / w, p["decay_sigma_per_s"] / w
                s.append(f'<line x1="{px(f):.1f}" y1="{py(z - dz):.1f}" x2="{px(f):.1f}" '
                         f'y2="{py(z + dz):.1f}" stroke="{c}"/>')
                s.append(f'<circle cx="{px(f):.1f}" cy="{py(z):.1f}" r="3.5" fill="{c}"/>')
        y = T + 14 + 16 * i
        s.append(f'<line x1="{L + 10}" y1="{y - 4}" x2="{L + 30}" y2="{y - 4}" stroke="{c}" '
                 f'stroke-width="2"/><text x="{L + 36}" y="{y}">{label}: {model}</text>')
    s.append("</svg>")
    with open(out, "w") as fh:
        fh.write("\n".join(s) + "\n")


if __name__ == "__main__":
    main()
