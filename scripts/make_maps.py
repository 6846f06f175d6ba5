#!/usr/bin/env python3
"""Writes the OpenDRIVE maps shipped in scenarios/maps/ (written by the project; MIT OR
Apache-2.0, as the rest of paracosm).

    python3 scripts/make_maps.py scenarios/maps

- bend.xodr: a two-lane road with sidewalks, 100 m straight, a 30 m spiral (curvature 0 to
  1/40 1/m), an arc of radius 40 m turning 1 rad, the mirror spiral, 100 m straight.
- junction.xodr: a four-way junction of two-lane arms (70 m each, sidewalks) whose
  connecting roads are lines (straight on) and quarter arcs (right and left turns).
- roundabout.xodr: a one-lane ring of radius 20 m, driven counter-clockwise, with four
  two-lane arms joined through four junctions (an entry, an exit and the ring's through road
  in each), the entry and exit arcs tangent to both arm and ring.

Start poses of every geometry record are computed here (spirals by Simpson's rule on 20,000
intervals), so that each record begins where the one before it ends.
"""

import math
import sys
from pathlib import Path

LANE = 3.5
WALK = 2.0


def spiral_end(x, y, hdg, length, k0, k1, n=20000):
    """End pose of a clothoid record, by Simpson's rule."""
    c = (k1 - k0) / length

    def theta(s):
        return hdg + k0 * s + 0.5 * c * s * s

    h = length / n
    sx = sy = 0.0
    for i in range(n + 1):
        w = 1 if i in (0, n) else (4 if i % 2 else 2)
        t = theta(i * h)
        sx += w * math.cos(t)
        sy += w * math.sin(t)
    return x + sx * h / 3, y + sy * h / 3, theta(length)


def arc_end(x, y, hdg, length, k):
    if abs(k) < 1e-15:
        return x + length * math.cos(hdg), y + length * math.sin(hdg), hdg
    h1 = hdg + k * length
    return (x + (math.sin(h1) - math.sin(hdg)) / k,
            y - (math.cos(h1) - math.cos(hdg)) / k, h1)


def f(v):
    return f"{v:.12f}"


def geometry(records, x, y, hdg):
    """records: ('line', L) | ('arc', L, k) | ('spiral', L, k0, k1). Returns XML, end pose."""
    out, s = [], 0.0
    for r in records:
        kind, length = r[0], r[1]
        head = f'      <geometry s="{f(s)}" x="{f(x)}" y="{f(y)}" hdg="{f(hdg)}" length="{f(length)}">'
        if kind == "line":
            body = "<line/>"
            x, y, hdg = arc_end(x, y, hdg, length, 0.0)
        elif kind == "arc":
            body = f'<arc curvature="{f(r[2])}"/>'
            x, y, hdg = arc_end(x, y, hdg, length, r[2])
        else:
            body = f'<spiral curvStart="{f(r[2])}" curvEnd="{f(r[3])}"/>'
            x, y, hdg = spiral_end(x, y, hdg, length, r[2], r[3])
        out.append(f"{head}{body}</geometry>")
        s += length
    return "\n".join(out), s, (x, y, hdg)


def lane(od_id, kind, width, pred=None, succ=None):
    link = ""
    if pred is not None or succ is not None:
        parts = []
        if pred is not None:
            parts.append(f'<predecessor id="{pred}"/>')
        if succ is not None:
            parts.append(f'<successor id="{succ}"/>')
        link = "<link>" + "".join(parts) + "</link>"
    return (f'          <lane id="{od_id}" type="{kind}" level="false">{link}'
            f'<width sOffset="0" a="{f(width)}" b="0" c="0" d="0"/></lane>')


def road(rid, records, x, y, hdg, lanes_left, lanes_right, junction="-1", link=""):
    geo, length, end = geometry(records, x, y, hdg)
    left = "\n".join(lanes_left)
    right = "\n".join(lanes_right)
    left_xml = f"        <left>\n{left}\n        </left>\n" if lanes_left else ""
    right_xml = f"        <right>\n{right}\n        </right>\n" if lanes_right else ""
    xml = f"""  <road name="{rid}" length="{f(length)}" id="{rid}" junction="{junction}">
    <link>{link}</link>
    <planView>
{geo}
    </planView>
    <lanes>
      <laneSection s="0">
{left_xml}        <center><lane id="0" type="none" level="false"/></center>
{right_xml}      </laneSection>
    </lanes>
  </road>"""
    return xml, end


def document(name, body):
    return f"""<?xml version="1.0" encoding="UTF-8"?>
<!-- {name}: written by scripts/make_maps.py for paracosm (MIT OR Apache-2.0). -->
<OpenDRIVE>
  <header revMajor="1" revMinor="6" name="{name}" version="1.0" vendor="paracosm"/>
{body}
</OpenDRIVE>
"""


def two_way(walk=True):
    left = [lane(1, "driving", LANE)] + ([lane(2, "sidewalk", WALK)] if walk else [])
    right = [lane(-1, "driving", LANE)] + ([lane(-2, "sidewalk", WALK)] if walk else [])
    return left, right


def bend():
    k = 1.0 / 40.0
    records = [("line", 100.0), ("spiral", 30.0, 0.0, k), ("arc", 40.0, k),
               ("spiral", 30.0, k, 0.0), ("line", 100.0)]
    left, right = two_way()
    xml, _ = road("1", records, 0.0, 0.0, 0.0, left, right)
    return document("bend", xml)


def junction():
    J, L = 12.0, 70.0
    roads, conns = [], []
    arms = {"E": 0.0, "N": math.pi / 2, "W": math.pi, "S": -math.pi / 2}
    ids = {"E": "1", "N": "2", "W": "3", "S": "4"}
    for a, h in arms.items():
        left, right = two_way()
        xml, _ = road(ids[a], [("line", L)], J * math.cos(h), J * math.sin(h), h, left, right,
                      link='<predecessor elementType="junction" elementId="100"/>')
        roads.append(xml)
    order = ["E", "N", "W", "S"]
    next_id = 10
    for i, a in enumerate(order):
        h = arms[a]
        start = (J * math.cos(h), J * math.sin(h), h + math.pi)
        # Straight on: the opposite arm; right: the arm clockwise after (coming from E heading
        # west, right is north); left: counter-clockwise.
        targets = [(order[(i + 2) % 4], ("line", 2 * J)),
                   (order[(i + 1) % 4], ("arc", math.pi / 2 * J, -1.0 / J)),
                   (order[(i + 3) % 4], ("arc", math.pi / 2 * J, 1.0 / J))]
        for b, rec in targets:
            cid = str(next_id)
            next_id += 1
            link = (f'<predecessor elementType="road" elementId="{ids[a]}" contactPoint="start"/>'
                    f'<successor elementType="road" elementId="{ids[b]}" contactPoint="start"/>')
            xml, end = road(cid, [rec], *start, [], [lane(-1, "driving", LANE, 1, -1)],
                            junction="100", link=link)
            hb = arms[b]
            want = (J * math.cos(hb), J * math.sin(hb))
            assert math.hypot(end[0] - want[0], end[1] - want[1]) < 1e-9, (a, b, end, want)
            roads.append(xml)
            conns.append(f'    <connection id="{cid}" incomingRoad="{ids[a]}" connectingRoad="{cid}" '
                         f'contactPoint="start"><laneLink from="1" to="-1"/></connection>')
    body = "\n".join(roads) + '\n  <junction id="100" name="cross">\n' + "\n".join(conns) + "\n  </junction>"
    return document("junction", body)


def roundabout():
    R, d, L = 20.0, 10.0, 60.0
    r = d * (2 * R + d) / (2 * R)  # the entry and exit arcs' radius, tangent to arm and ring
    a = math.atan2(r, R + d)  # angle from an arm to where its entry meets the ring
    turn = math.pi / 2 - a  # how far the entry and exit turn
    roads, junctions = [], []
    thetas = [0.0, math.pi / 2, math.pi, 3 * math.pi / 2]
    ring_lanes = ([], [lane(-1, "driving", LANE, -1, -1)])
    for k, th in enumerate(thetas):
        jid = str(100 + k)
        arm, ring_out = str(1 + k), str(10 + k)  # ring_out: from this junction to the next
        through, entry, exit_ = str(20 + k), str(30 + k), str(40 + k)
        ring_in = str(10 + (k - 1) % 4)
        left, right = two_way()
        xml, _ = road(arm, [("line", L)], (R + d) * math.cos(th), (R + d) * math.sin(th), th,
                      left, right, link=f'<predecessor elementType="junction" elementId="{jid}"/>')
        roads.append(xml)
        # The ring from this junction's end (th + a) to the next one's start (th + 90° - a).
        p0 = th + a
        xml, end = road(ring_out, [("arc", R * (math.pi / 2 - 2 * a), 1.0 / R)],
                        R * math.cos(p0), R * math.sin(p0), p0 + math.pi / 2, *ring_lanes,
                        link=(f'<predecessor elementType="junction" elementId="{jid}"/>'
                              f'<successor elementType="junction" elementId="{100 + (k + 1) % 4}"/>'))
        roads.append(xml)
        # The ring's road through the junction, th - a to th + a.
        pm = th - a
        link = (f'<predecessor elementType="road" elementId="{ring_in}" contactPoint="end"/>'
                f'<successor elementType="road" elementId="{ring_out}" contactPoint="start"/>')
        xml, end = road(through, [("arc", R * 2 * a, 1.0 / R)], R * math.cos(pm), R * math.sin(pm),
                        pm + math.pi / 2, [], [lane(-1, "driving", LANE, -1, -1)], junction=jid, link=link)
        assert abs(end[0] - R * math.cos(p0)) < 1e-9 and abs(end[1] - R * math.sin(p0)) < 1e-9
        roads.append(xml)
        # Entry: from the arm's end heading in, turning right onto the ring.
        link = (f'<predecessor elementType="road" elementId="{arm}" contactPoint="start"/>'
                f'<successor elementType="road" elementId="{ring_out}" contactPoint="start"/>')
        xml, end = road(entry, [("arc", r * turn, -1.0 / r)], (R + d) * math.cos(th),
                        (R + d) * math.sin(th), th + math.pi, [], [lane(-1, "driving", LANE, 1, -1)],
                        junction=jid, link=link)
        assert abs(end[0] - R * math.cos(p0)) < 1e-9 and abs(end[1] - R * math.sin(p0)) < 1e-9, end
        roads.append(xml)
        # Exit: from the ring at th - a, turning right out along the arm.
        link = (f'<predecessor elementType="road" elementId="{ring_in}" contactPoint="end"/>'
                f'<successor elementType="road" elementId="{arm}" contactPoint="start"/>')
        xml, end = road(exit_, [("arc", r * turn, -1.0 / r)], R * math.cos(pm), R * math.sin(pm),
                        pm + math.pi / 2, [], [lane(-1, "driving", LANE, -1, -1)], junction=jid, link=link)
        assert abs(end[0] - (R + d) * math.cos(th)) < 1e-9 and abs(end[1] - (R + d) * math.sin(th)) < 1e-9, end
        roads.append(xml)
        junctions.append(
            f'  <junction id="{jid}" name="ring {k}">\n'
            f'    <connection id="1" incomingRoad="{ring_in}" connectingRoad="{through}" contactPoint="start"><laneLink from="-1" to="-1"/></connection>\n'
            f'    <connection id="2" incomingRoad="{ring_in}" connectingRoad="{exit_}" contactPoint="start"><laneLink from="-1" to="-1"/></connection>\n'
            f'    <connection id="3" incomingRoad="{arm}" connectingRoad="{entry}" contactPoint="start"><laneLink from="1" to="-1"/></connection>\n'
            f'  </junction>')
    return document("roundabout", "\n".join(roads) + "\n" + "\n".join(junctions))


def main():
    out = Path(sys.argv[1] if len(sys.argv) > 1 else "scenarios/maps")
    out.mkdir(parents=True, exist_ok=True)
    for name, text in [("bend", bend()), ("junction", junction()), ("roundabout", roundabout())]:
        (out / f"{name}.xodr").write_text(text)
        print(f"wrote {out / (name + '.xodr')}")


if __name__ == "__main__":
    main()
