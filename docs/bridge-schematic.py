#!/usr/bin/env python3
"""Draws docs/bridge-schematic.svg, the reference bridge of docs/hardware.md, from this file.

Run `python3 docs/bridge-schematic.py` after changing it; the SVG is written beside it. Plain
Python 3, no packages: boxes, wires and labels placed by hand on a 10-unit grid.
"""
import os

W, H = 1200, 860
out = []


def box(x, y, w, h, title, lines=(), fill="#f7f7f7", stroke="#222"):
    out.append(f'<rect x="{x}" y="{y}" width="{w}" height="{h}" rx="6" fill="{fill}" stroke="{stroke}" stroke-width="1.5"/>')
    out.append(f'<text x="{x + w / 2}" y="{y + 18}" text-anchor="middle" font-weight="bold">{title}</text>')
    for i, line in enumerate(lines):
        out.append(f'<text x="{x + 8}" y="{y + 36 + 15 * i}" font-size="11">{line}</text>')


def wire(points, label=None, dash=False, color="#222"):
    d = " ".join(f"{x},{y}" for x, y in points)
    extra = ' stroke-dasharray="6,4"' if dash else ""
    out.append(f'<polyline points="{d}" fill="none" stroke="{color}" stroke-width="1.5"{extra} marker-end="url(#arrow)"/>')
    if label:
        (x0, y0), (x1, y1) = points[0], points[1]
        out.append(f'<text x="{(x0 + x1) / 2 + 4}" y="{(y0 + y1) / 2 - 4}" font-size="11" fill="{color}">{label}</text>')


def note(x, y, text, size=11, color="#444"):
    out.append(f'<text x="{x}" y="{y}" font-size="{size}" fill="{color}">{text}</text>')


# Isolation barrier between the laptop and the machine's PELV side.
out.append(f'<line x1="250" y1="40" x2="250" y2="{H - 40}" stroke="#b00" stroke-width="2" stroke-dasharray="10,6"/>')
note(150, 60, "laptop side", 12, "#b00")
note(262, 60, "machine side: PELV, 24 V from the cabinet", 12, "#b00")

box(30, 90, 190, 80, "Laptop", ["Chrome (WebSerial) or", "cutlab host --port"])
box(30, 220, 190, 90, "USB isolator", ["e.g. ADuM4160 module,", "≥ 2.5 kV isolation", "(laptop ground never", "joins the machine's)"], fill="#fff4f4")
wire([(125, 170), (125, 220)], "USB")
wire([(220, 265), (300, 265)], "USB full speed")

box(300, 200, 240, 170, "Microcontroller", ["USB CDC-ACM, protocol 2.0 codec", "ADC ≥ 10 kS/s per channel,", "RMS at the ADC rate", "independent watchdog (IWDG) on",
                                              "pull-downs on every output:", "outputs OFF in reset and boot", "toggles WDI while healthy", "reads: in-cycle, M30, F, S, feed"])
box(300, 420, 240, 80, "Isolated DC/DC", ["24 V cabinet → 5 V / ±15 V", "(PELV, one protective-earth", "point at the bridge's DIN rail)"], fill="#fff4f4")
wire([(420, 420), (420, 370)], "5 V")

box(600, 90, 250, 90, "Retriggerable monostable", ["74HC123, RC about 50 ms:", "HEALTHY stays high only while", "WDI toggles (a hung or resetting", "MCU drops it)"], fill="#eef6ff")
wire([(540, 230), (600, 150)], "WDI (toggle each loop)")
box(600, 220, 250, 70, "AND gate", ["74HC08: HEALTHY AND ARMED", "→ RELAY ENABLE (24 V driver)"], fill="#eef6ff")
wire([(725, 180), (725, 220)], "HEALTHY")
wire([(540, 270), (600, 260)], "ARMED")

box(900, 200, 270, 140, "Force-guided changeover relays", ["K1…K4 (dial mode) or K5 = EN", "(ladder mode), e.g. Phoenix", "PSR / Finder 7S:", "de-energised (NC): operator's", "dial to the PMC; energised (NO):", "bridge's optos to the PMC"], fill="#eefaee")
wire([(850, 255), (900, 255)], "ENABLE")
box(600, 330, 250, 80, "Opto-couplers", ["one per PMC input, its own pin,", "sinking or sourcing as the", "existing switch is (1 = conducting", "= input energised)"])
wire([(540, 350), (600, 360)], "D0…D7 / code")
wire([(850, 370), (900, 320)], "to relay NO")
box(900, 380, 270, 70, "PMC inputs (the ladder)", ["check every bit on the PMC", "diagnosis screen before a cut"], fill="#eefaee")
wire([(1035, 340), (1035, 380)])

box(600, 470, 250, 110, "Feed-hold latch", ["safety relay with NC contact in", "the feed-hold chain, latching;", "opens on HOLD (over-current,", "overload, fallback limit) or on", "loss of HEALTHY; reset button"], fill="#fff8e6")
wire([(540, 480), (600, 500)], "HOLD")
box(900, 490, 270, 70, "Machine feed-hold chain", ["*SP in series: the NC contact", "holds G00 too; E-stop separate"], fill="#fff8e6")
wire([(850, 525), (900, 525)], "NC contact")
note(612, 600, "reset: a pushbutton at the machine, read by the MCU (firmware latch follows)", 11)

box(300, 560, 240, 130, "Current channels (×3 per drive)", ["closed-loop Hall transducers,", "rated above peak current,", "on the amplifier terminals:", "burden R, op-amp shift to mid-rail,", "RC anti-alias, ADC", "open-sensor comparator: supply", "current out of range → fault"], fill="#f3efff")
wire([(420, 560), (420, 500)], None, dash=True)
note(310, 715, "three transducers per drive: the phases must sum to ~0 (sensor fault otherwise)", 11)

box(30, 560, 220, 110, "Drives (cabinet)", ["spindle and feed amplifiers", "DC link 300–600 V: lock out,", "tag out, wait, measure before", "touching the terminals", "(qualified electrician)"], fill="#ffeeee")
wire([(250, 620), (300, 620)], "phase leads through transducers")

box(30, 740, 520, 80, "Control signals read by the bridge (declared in `measured`)", ["in-cycle and program end (M30) outputs, programmed F and S words or speed output,", "actual feed (control's output or encoder), override read back: without them the host", "refuses to arm (stuck override unseen)"], fill="#f7f7f7")
wire([(420, 740), (420, 690)], None, dash=True)

note(600, 680, "Outputs default OFF: pull-downs hold every output low through reset, boot-loader", 11)
note(600, 696, "and a port opening that resets the board; HEALTHY cannot rise before the firmware", 11)
note(600, 712, "toggles WDI, so ENABLE and the relays stay de-energised until it runs.", 11)
note(600, 740, "This loop is not a safety function (ISO 13849): the E-stop chain stays the machine's own.", 12, "#b00")

svg = f'''<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{H}" viewBox="0 0 {W} {H}" font-family="sans-serif" font-size="12">
<title>The reference bridge: a fail-safe override and feed-hold path (docs/hardware.md)</title>
<defs><marker id="arrow" markerWidth="8" markerHeight="8" refX="7" refY="4" orient="auto"><path d="M0,0 L8,4 L0,8 z" fill="#222"/></marker></defs>
<rect width="{W}" height="{H}" fill="white"/>
<text x="{W / 2}" y="24" text-anchor="middle" font-size="16" font-weight="bold">cutlab bridge — reference design (block schematic)</text>
''' + "\n".join(out) + "\n</svg>\n"

with open(os.path.join(os.path.dirname(os.path.abspath(__file__)), "bridge-schematic.svg"), "w", encoding="utf-8") as f:
    f.write(svg)
