#!/usr/bin/python3
"""Penalty contact between bodies stepped at different rates: which scheme keeps the energy.

A 1D model of the question multiple time stepping must answer (docs/solver.md, "Pairs across
levels"): an elastic bar A of fine elements (level 0, step h) strikes an elastic bar B of elements
`ratio` times longer, whose own stable step is `ratio` times A's, through a penalty spring at their
touching ends (stiffness 0.5 E / h_A, as the FE contact's). Lumped masses, linear springs, unit
density and modulus; A at 0.3 of the wave speed against B at rest ("impact"), or both moving
toward each other ("pressed": a longer contact). Every scheme runs to the same time, a multiple of
every step, where all velocities are synchronous; the energy error is (E_end - E_0) / E_0, the
depth is the deepest overlap in A's element lengths.

  single  every element and the pair at h (the reference);
  wait    B steps once per window of ratio * h, its nodes waiting at the window's start; the pair
          at h against B's waiting node, its impulses on B summed and applied at B's step;
  avi     asynchronous variational integrator (Lew, Marsden, Ortiz & West 2003): every node
          drifts at every base step, each element and the pair give their impulse (step * force)
          at their own times, the pair at h; B's elements at ratio * h;
  avi+N   the same with B's N elements nearest the contact ("the ring") at the pair's step h.

    /usr/bin/python3 tools/studies/mts_contact_1d.py [--json FILE]
"""
import argparse
import json
import os

import numpy as np

N_A = 40  # A's elements (length 1)


def bars(ratio):
    h_a = 1.0 / N_A
    h_b = h_a * ratio
    n_b = max(2, 20 // ratio)  # B about half A's length
    x = np.concatenate([np.arange(N_A + 1) * h_a - 1.0 - 1e-3, np.arange(n_b + 1) * h_b])
    m = np.concatenate([np.full(N_A + 1, h_a), np.full(n_b + 1, h_b)])
    m[[0, N_A, N_A + 1, -1]] /= 2.0
    # springs (left node, right node, stiffness E / length, B's index from the contact or -1)
    springs = [(i, i + 1, 1.0 / h_a, -1) for i in range(N_A)]
    springs += [(N_A + 1 + j, N_A + 2 + j, 1.0 / h_b, j) for j in range(n_b)]
    return h_a, x, m, springs


def energy(x, x0, v, m, springs, k):
    e = 0.5 * np.sum(m * v * v)
    for i, j, kk, _ in springs:
        e += 0.5 * kk * ((x[j] - x[i]) - (x0[j] - x0[i])) ** 2
    overlap = x[N_A] - x[N_A + 1]
    return e + (0.5 * k * overlap * overlap if overlap > 0 else 0.0)


def run(scheme, ratio, pressed, duration=4.0, speed=0.3):
    h_a, x, m, springs = bars(ratio)
    x0 = x.copy()
    v = np.zeros_like(x)
    v[: N_A + 1] = speed
    if pressed:
        v[N_A + 1:] = -speed
    k = 0.5 / h_a
    h = 0.9 * h_a
    ring = int(scheme.split("+")[1]) if "+" in scheme else 0
    coarse = 1 if scheme == "single" else ratio
    e0 = energy(x, x0, v, m, springs, k)
    steps = int(round(duration / h / coarse)) * coarse
    deepest = 0.0
    if scheme == "wait":
        return wait(x, x0, v, m, springs, k, h, ratio, steps, e0, h_a)
    for n in range(steps + 1):
        # impulses of the potentials due: step * force, half at the start and at the end
        for i, j, kk, b in springs:
            every = coarse if b >= ring else 1
            if n % every == 0:
                tau = every * h * (0.5 if n in (0, steps) else 1.0)
                f = kk * ((x[j] - x[i]) - (x0[j] - x0[i]))
                v[i] += tau * f / m[i]
                v[j] -= tau * f / m[j]
        overlap = x[N_A] - x[N_A + 1]
        deepest = max(deepest, overlap)
        if overlap > 0:
            tau = h * (0.5 if n in (0, steps) else 1.0)
            v[N_A] -= tau * k * overlap / m[N_A]
            v[N_A + 1] += tau * k * overlap / m[N_A + 1]
        if n < steps:
            x += h * v
    return (energy(x, x0, v, m, springs, k) - e0) / e0, deepest / h_a


def wait(x, x0, v, m, springs, k, h, ratio, steps, e0, h_a):
    """B waits at its window's start; the pair's impulses on it are applied at its step."""
    a_nodes = slice(0, N_A + 1)
    b_nodes = slice(N_A + 1, None)

    def forces(nodes_springs):
        f = np.zeros_like(x)
        for i, j, kk, _ in nodes_springs:
            t = kk * ((x[j] - x[i]) - (x0[j] - x0[i]))
            f[i] += t
            f[j] -= t
        return f

    a_springs = [s for s in springs if s[3] < 0]
    b_springs = [s for s in springs if s[3] >= 0]
    f_a, f_b = forces(a_springs), forces(b_springs)
    summed = 0.0
    deepest = 0.0
    window = ratio * h
    for n in range(steps):
        overlap = x[N_A] - x[N_A + 1]
        p = k * overlap if overlap > 0 else 0.0
        v[a_nodes] += 0.5 * h * f_a[a_nodes] / m[a_nodes]
        v[N_A] -= 0.5 * h * p / m[N_A]
        x[a_nodes] += h * v[a_nodes]
        f_a = forces(a_springs)
        overlap = x[N_A] - x[N_A + 1]
        deepest = max(deepest, overlap)
        p = k * overlap if overlap > 0 else 0.0
        v[a_nodes] += 0.5 * h * f_a[a_nodes] / m[a_nodes]
        v[N_A] -= 0.5 * h * p / m[N_A]
        summed += h * p
        if (n + 1) % ratio == 0:  # B's step over the window, the pair's impulse as a held force
            held = np.zeros_like(x)
            held[N_A + 1] = summed / window
            v[b_nodes] += 0.5 * window * (f_b[b_nodes] + held[b_nodes]) / m[b_nodes]
            x[b_nodes] += window * v[b_nodes]
            f_b = forces(b_springs)
            v[b_nodes] += 0.5 * window * (f_b[b_nodes] + held[b_nodes]) / m[b_nodes]
            summed = 0.0
    return (energy(x, x0, v, m, springs, k) - e0) / e0, deepest / h_a


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--json", help="write the table as JSON to this file")
    args = parser.parse_args()
    rows = []
    print("%-8s %5s %-7s %14s %12s" % ("case", "ratio", "scheme", "energy error", "depth / h_A"))
    for pressed in (False, True):
        for ratio in (2, 4, 8):
            for scheme in ("single", "wait", "avi", "avi+1", "avi+2"):
                error, depth = run(scheme, ratio, pressed)
                case = "pressed" if pressed else "impact"
                rows.append({"case": case, "ratio": ratio, "scheme": scheme,
                             "energy_error": error, "depth": depth})
                print("%-8s %5d %-7s %+14.2e %12.3f" % (case, ratio, scheme, error, depth))
    if args.json:
        with open(args.json + ".tmp", "w", encoding="utf-8") as f:
            json.dump(rows, f, indent=1)
        os.replace(args.json + ".tmp", args.json)


if __name__ == "__main__":
    main()
