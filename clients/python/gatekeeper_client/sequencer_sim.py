"""A Phase-3 sequencer simulator: for sample parts it enumerates bend orders, validates each
branch with gatekeeperd, prunes on failure, tries the corrections the gatekeeper suggests, and
prints a table of every step plus the best feasible sequence.

    gatekeeper-sequencer-sim [--address 127.0.0.1:50051] [--orders N]
"""
import argparse
import itertools
import math
import sys
import time
import tomllib

from gatekeeper_client.connection import add_connection_arguments, connect_from_arguments, pb

SIDES = {"Y_MAX": pb.Y_MAX, "Y_MIN": pb.Y_MIN, "X_MAX": pb.X_MAX, "X_MIN": pb.X_MIN}


class Part:
    """A blank and the flanges planned on it; the flange material belongs to the blank until bent."""

    def __init__(self, name, width, depth, thickness, planned, tabs=()):
        self.name, self.width, self.depth, self.thickness = name, width, depth, thickness
        self.planned = planned  # [(side, height, angle)], angle > 0 up, < 0 down
        self.tabs = tabs

    def relief(self, side):
        """Flanges stop short of the perpendicular flanges (a corner relief of their height + 1 mm)."""
        across = ("X_MIN", "X_MAX") if side.startswith("Y") else ("Y_MIN", "Y_MAX")
        return max([h for s, h, _ in self.planned if s in across] + [0.0]) + 1.0


def blank_after(part, bent):
    """Blank size and flange messages once `bent` (a list of planned flanges) are bent."""
    w, d = part.width, part.depth
    for side, h, _ in bent:
        if side.startswith("Y"):
            d -= h
        else:
            w -= h
    flanges = []
    for side, h, angle in bent:
        edge = w if side.startswith("Y") else d
        r = part.relief(side)
        flanges.append(pb.Flange(side=SIDES[side], height_mm=h, angle_deg=angle, start_mm=r, length_mm=max(edge - 2 * r, 1.0)))
    return w, d, flanges


def bend_line(side, w, d, h):
    """Bend point and direction in part coordinates: the flange (moving side) lies left of the direction."""
    return {
        "Y_MAX": ((0.0, d - h), (1.0, 0.0)),
        "Y_MIN": ((0.0, h), (-1.0, 0.0)),
        "X_MAX": ((w - h, 0.0), (0.0, -1.0)),
        "X_MIN": ((h, 0.0), (0.0, 1.0)),
    }[side]


def aba_span(slots, length):
    """Engage the slots lying within the bend length, 5 mm short at each end."""
    return [lo >= -length / 2 + 5.0 and hi <= length / 2 - 5.0 for lo, hi in slots]


def grip_y(held_depth):
    """The manipulator point across the bend line: on the held side, at least 400 mm back (where
    the rotator column clears the blankholder), within the manipulator's travel."""
    return max(-2200.0, min(-50.0, -max(400.0, 0.5 * held_depth)))


def branch_steps(part, order, slots):
    """Every step of one bend order: for each flange CLAMP and BEND, then ROTATE to the next side."""
    steps = []
    for k, (side, h, angle) in enumerate(order):
        w, d, flanges = blank_after(part, order[:k])
        sheet = pb.SheetPart(width_mm=w, depth_mm=d, thickness_mm=part.thickness, flanges=flanges,
                             tabs=[pb.Tab(**t) for t in part.tabs] if k == 0 else [])
        (px, py), (dx, dy) = bend_line(side, w, d, h)
        length = w if side.startswith("Y") else d
        held = (d if side.startswith("Y") else w) - h
        state = pb.MachineState(engaged_segments=aba_span(slots, length), clamp_z_mm=part.thickness,
                                manipulator_y_mm=grip_y(held))
        base = dict(bend_point=pb.Vec2(x_mm=px, y_mm=py), bend_direction=pb.Vec2(x_mm=dx, y_mm=dy))
        steps.append(("CLAMP " + side, pb.ValidateStepRequest(part=sheet, state=state, step=pb.Step(kind=pb.CLAMP, **base))))
        kind = pb.BEND_UP if angle > 0 else pb.BEND_DOWN
        steps.append((("BEND_UP " if angle > 0 else "BEND_DOWN ") + side,
                      pb.ValidateStepRequest(part=sheet, state=state,
                                             step=pb.Step(kind=kind, target_angle_deg=abs(angle), **base))))
        if k + 1 < len(order):
            w2, d2, flanges2 = blank_after(part, order[:k + 1])
            bent = pb.SheetPart(width_mm=w2, depth_mm=d2, thickness_mm=part.thickness, flanges=flanges2)
            steps.append(("ROTATE", pb.ValidateStepRequest(part=bent, state=state,
                                                           step=pb.Step(kind=pb.ROTATE, rotate_angle_deg=90.0, **base))))
    return steps


def correction_requests(request, correction):
    """The correction's sub-sequence as requests, each step in its own machine state. FLIP turns
    the bend into an up-bend of the turned part (its flanges' angles change sign)."""
    out = []
    for cs in correction.steps:
        fixed = pb.ValidateStepRequest()
        fixed.CopyFrom(request)
        fixed.step.CopyFrom(cs.step)
        fixed.state.CopyFrom(cs.state)
        fixed.skip_corrections = True
        if cs.part_turned_over:
            for f in fixed.part.flanges:
                f.angle_deg = -f.angle_deg
        out.append(fixed)
    return out


CORRECTION = {pb.CORRECTION_NONE: "-", pb.REPO: "REPO", pb.CHANGE_ABA: "CHANGE_ABA", pb.RETRACT_FIRST: "RETRACT", pb.FLIP: "FLIP"}
VERDICT = {pb.CLEAR: "CLEAR", pb.TOUCHING: "TOUCHING", pb.COLLISION: "COLLISION", pb.INCONCLUSIVE: "INCONCLUSIVE"}


def run_branch(stub, part, order, slots, rows, label):
    """Validates a branch step by step; a failure is retried once with its verified correction.
    A FLIP turns the part over: that flange is then bent up, and later steps see it so."""
    order = list(order)
    corrections, total_us, index = 0, 0.0, 0
    while True:
        steps = branch_steps(part, order, slots)
        if index >= len(steps):
            return True, corrections, total_us
        name, request = steps[index]
        index += 1
        started = time.perf_counter()
        answer = stub.ValidateStep(request, timeout=10.0)
        latency_us = (time.perf_counter() - started) * 1e6
        total_us += latency_us
        organ = answer.collisions[0].organ if answer.collisions else ""
        angle = f"{answer.collisions[0].first_contact_deg:.2f}" if answer.collisions and "BEND" in name else ""
        fix = answer.correction
        rows.append((label, name, VERDICT[answer.verdict], organ, angle,
                     CORRECTION[fix.kind] + (" (verified)" if fix.verified else ""), f"{latency_us:.0f}"))
        if answer.verdict == pb.CLEAR:
            continue
        if answer.verdict == pb.COLLISION and fix.verified and fix.kind != pb.CORRECTION_NONE:
            if fix.kind == pb.FLIP:  # verified by the gatekeeper on the turned-over part
                rows.append((label, name + " + FLIP", "CLEAR", "", "", "-", ""))
                side = name.split()[-1]
                order = [(s, h, abs(a)) if s == side else (s, h, a) for s, h, a in order]
                corrections += 1
                continue
            # Run the sub-sequence the gatekeeper verified, step by step, as the machine would.
            all_clear = True
            for sub in correction_requests(request, fix):
                retried = stub.ValidateStep(sub, timeout=10.0)
                rows.append((label, f"  {CORRECTION[fix.kind]}: {pb.StepKind.Name(sub.step.kind)}",
                             VERDICT[retried.verdict], "", "", "-", ""))
                all_clear = all_clear and retried.verdict == pb.CLEAR
            if all_clear:
                corrections += 1
                continue
        return False, corrections, total_us  # pruned


def sample_parts():
    return [
        Part("tray 800x600", 800.0, 600.0, 1.5, [("Y_MAX", 40.0, 90.0), ("Y_MIN", 40.0, 90.0), ("X_MAX", 40.0, 90.0), ("X_MIN", 40.0, 90.0)]),
        Part("panel with a deep return 1200x900", 1200.0, 900.0, 1.5,
             [("Y_MAX", 60.0, 90.0), ("Y_MIN", 170.0, -90.0), ("X_MAX", 50.0, 90.0)]),
        Part("cover with a tab 900x600", 900.0, 600.0, 1.0, [("Y_MAX", 50.0, 90.0)],
             tabs=[dict(x_min_mm=440.0, x_max_mm=460.0, y_mm=530.0, height_mm=30.0)]),
    ]


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_connection_arguments(parser)
    parser.add_argument("--orders", type=int, default=6, help="bend orders tried per part")
    args = parser.parse_args(argv)
    stub, _ = connect_from_arguments(args)
    machine = stub.GetMachine(pb.GetMachineRequest(), timeout=5.0)
    model = tomllib.loads(machine.model_toml)
    widths = model["aba"]["segment_widths_mm"]
    x = -sum(widths) / 2.0
    slots = []
    for w in widths:
        slots.append((x, x + w))
        x += w
    print(f"gatekeeperd at {args.address}: machine {machine.machine_id} ({machine.name}), {machine.aba_segments} ABA segments")
    parts_without_sequence = 0
    for part in sample_parts():
        rows, feasible = [], []
        for n, order in enumerate(itertools.islice(itertools.permutations(part.planned), args.orders)):
            label = f"{n}:" + ">".join(s for s, _, _ in order)
            ok, corrections, total_us = run_branch(stub, part, order, slots, rows, label)
            if ok:
                feasible.append((corrections, total_us, label))
        print(f"\n== {part.name}: {len(feasible)} of {min(args.orders, math.factorial(len(part.planned)))} bend orders feasible")
        header = ("branch", "step", "verdict", "organ", "contact deg", "correction", "latency us")
        widths_ = [max(len(str(r[i])) for r in rows + [header]) for i in range(len(header))]
        for r in [header] + rows:
            print("  ".join(str(c).ljust(widths_[i]) for i, c in enumerate(r)))
        if feasible:
            best = min(feasible)
            print(f"best feasible sequence: {best[2]} ({best[0]} corrections, {best[1]:.0f} us of gatekeeping)")
        else:
            print("no feasible sequence among the orders tried")
            parts_without_sequence += 1
    info = stub.GetServerInfo(pb.GetServerInfoRequest(), timeout=5.0)
    for r in info.rpcs:
        print(f"server: {r.method}: {r.calls} calls, p50 {r.p50_us:.0f} us, p99 {r.p99_us:.0f} us")
    # Exit status 1 when some part found no feasible bend order (a planner would have to stop).
    return 1 if parts_without_sequence else 0


if __name__ == "__main__":
    sys.exit(main())
