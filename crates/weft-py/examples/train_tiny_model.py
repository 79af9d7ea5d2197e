#!/usr/bin/env python3
"""Simulate a few garments with weft, then train a tiny PyTorch model on them.

    pip install ./crates/weft-py torch
    python crates/weft-py/examples/train_tiny_model.py --out /tmp/tiny

1. weft.generate_garment makes skirts of different styles (seeds), weft.simulate drapes
   each on the default body walking (weft.procedural_motion): the ground truth.
2. A per-vertex MLP learns the garment's displacement from its rest shape (after the
   body's root translation) from the vertex's rest position and the body pose.
3. It is scored on a skirt it never saw, against the rigid baseline (rest shape carried
   by the root translation), and the last frame is drawn with weft.render next to the
   simulation.

A toy on purpose: a few seconds of data, one small network, no hierarchy. It shows the
data path from weft into PyTorch; weft's own models (`weft train`) are what to use for
real results.
"""
import argparse
import sys
import time
from pathlib import Path

import numpy as np

import weft


def simulate_garments(seeds, frames, vertices, motion):
    """(garment, positions (T, N, 3)) for a skirt of each seed."""
    out = []
    for seed in seeds:
        garment = weft.generate_garment("skirt", vertices=vertices, seed=seed)
        started = time.time()
        positions, _ = weft.simulate(garment, motion, material="cotton", substeps=2, warmup=3)
        print(f"simulated skirt seed {seed}: {garment.vertex_count} vertices, {frames} frames "
              f"in {time.time() - started:.1f} s", file=sys.stderr)
        out.append((garment, positions))
    return out


def features(garment, motion):
    """Per frame and vertex: rest position (3) and the pose (72) -> (T, N, 75)."""
    rest = garment.positions
    poses = motion.poses.reshape(len(motion), 72)
    t, n = len(motion), rest.shape[0]
    return np.concatenate(
        [np.broadcast_to(rest, (t, n, 3)), np.broadcast_to(poses[:, None, :], (t, n, 72))], axis=2
    ).astype(np.float32)


def targets(garment, motion, positions):
    """Displacement from the rest shape carried by the root translation: (T, N, 3)."""
    carried = garment.positions[None] + (motion.trans - motion.trans[0])[:, None, :]
    return (positions - carried).astype(np.float32), carried


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--garments", type=int, default=3, help="training skirts")
    parser.add_argument("--frames", type=int, default=12)
    parser.add_argument("--vertices", type=int, default=400)
    parser.add_argument("--steps", type=int, default=300)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--out", type=Path, default=Path("tiny-model"))
    args = parser.parse_args()
    try:
        import torch
    except ImportError:
        print("error: this example trains with PyTorch; install it with `pip install torch`", file=sys.stderr)
        return 2
    torch.manual_seed(args.seed)
    args.out.mkdir(parents=True, exist_ok=True)

    motion = weft.procedural_motion("walk", frames=args.frames, seed=args.seed)
    train = simulate_garments(range(1, args.garments + 1), args.frames, args.vertices, motion)
    (test_garment, test_positions), = simulate_garments([100], args.frames, args.vertices, motion)

    x = torch.from_numpy(np.concatenate([features(g, motion).reshape(-1, 75) for g, _ in train]))
    y = torch.from_numpy(np.concatenate([targets(g, motion, p)[0].reshape(-1, 3) for g, p in train]))
    model = torch.nn.Sequential(
        torch.nn.Linear(75, 64), torch.nn.Tanh(), torch.nn.Linear(64, 64), torch.nn.Tanh(), torch.nn.Linear(64, 3)
    )
    optimiser = torch.optim.Adam(model.parameters(), lr=3e-3)
    for step in range(1, args.steps + 1):
        batch = torch.randint(0, x.shape[0], (4096,))
        loss = torch.nn.functional.mse_loss(model(x[batch]), y[batch])
        optimiser.zero_grad()
        loss.backward()
        optimiser.step()
        if step % 50 == 0 or step == 1:
            print(f"step {step}: loss {loss.item():.3e} (RMS {1e3 * loss.item() ** 0.5:.1f} mm)")

    # Score on the unseen skirt.
    y_test, carried = targets(test_garment, motion, test_positions)
    with torch.no_grad():
        predicted = model(torch.from_numpy(features(test_garment, motion))).numpy()
    error = np.linalg.norm(carried + predicted - test_positions, axis=2).mean() * 1e3
    baseline = np.linalg.norm(carried - test_positions, axis=2).mean() * 1e3
    print(f"unseen skirt: mean vertex error {error:.2f} mm (rigid baseline {baseline:.2f} mm)")

    body = weft.Body()
    posed = body.pose(motion.poses, motion.trans)[-1]
    for name, garment_frame in [("simulated", test_positions[-1]), ("predicted", carried[-1] + predicted[-1])]:
        path = args.out / f"last_frame_{name}.png"
        weft.render([(garment_frame, test_garment.faces), (posed, body.faces)], width=400, height=400, path=path)
        print(f"wrote {path}")
    return 0 if error < baseline else 1


if __name__ == "__main__":
    sys.exit(main())
