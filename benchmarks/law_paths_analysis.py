"""Where the law's support falls off the unforced law search's paths (one saved search).

Reads an ``.npz`` of ``law_paths_probe.py`` and a list of true term names; prints the true
support's noise ratio (all rows, held out), the full pencil's smallest ratios, the backward
path's step at which a true column is first eliminated, the forward path's position of each
true column, the admissible lasso's starts and what they lack, and the search's choice.

    PYTHONPATH=$PWD python benchmarks/law_paths_analysis.py \
        /tmp/lp/half_car_unforced_0.01_0_split0.npz half_car [out.jsonl]
"""
from __future__ import annotations

import sys

import numpy as np

from pysindy_xl.optimizers import homogeneous as hg
from pysindy_xl.optimizers._sparse import triangular_factor
from pysindy_xl.optimizers.laws import definite_mass, explained_coordinates
from pysindy_xl.optimizers.noise_ratio import (
    law_elimination_path,
    law_forward_path,
    noise_pencil,
    noise_ratio_law,
)

TRUTH = {"half_car": ["L[z_dot**2]", "L[theta_dot**2]", "L[zf_dot**2]", "L[zr_dot**2]",
                      "L[z**2]", "L[sin(theta)**2]", "L[z*sin(theta)]", "L[z*zf]", "L[z*zr]",
                      "L[zf*sin(theta)]", "L[zr*sin(theta)]", "L[zf**2]", "L[zr**2]",
                      "C_z[z_dot]", "C_theta[theta_dot]", "C_zf[zf_dot]", "C_zr[zr_dot]"]}


def prepared(data):
    """select_law's own scaling of the columns and moments."""
    theta = np.asarray(data["theta"], dtype=float)
    n_blocks = int(data["n_blocks"])
    nonzero = np.flatnonzero(np.any(theta != 0, axis=0))
    theta = theta[:, nonzero]
    moments = np.asarray(data["moments"], dtype=float)[:, nonzero][:, :, nonzero]
    scale = np.sqrt(np.mean(theta**2, axis=0))
    theta = theta / scale
    moments = moments / np.outer(scale, scale)[None]
    floor = 1e-10 * np.mean(np.diagonal(moments, axis1=1, axis2=2)) / len(moments)
    moments = moments + floor * np.eye(theta.shape[1])[None]
    draws = data["draws"][:, :, nonzero] / scale if "draws" in data else None
    rows = hg.RowMoments(draws, floor * n_blocks / theta.shape[0]) if draws is not None else None
    mass = data["mass_matrices"][:, nonzero] / scale[None, :, None, None]
    return theta, moments, rows, mass, nonzero, n_blocks


def block_balance(theta, moments, support, n_blocks, iterations=10):
    """Block weights that give the support's smallest-ratio law the same noise in every block
    (each coordinate's equation whitened by its own noise, as York's weighted errors-in-variables
    fit weights each equation), the law, its ratio and each block's own ratio under them.
    """
    rows = theta.shape[0] // n_blocks
    weights = np.ones(n_blocks)
    for _ in range(iterations):
        weighted = theta * np.repeat(weights, rows)[:, None]
        pooled = np.einsum("b,bfg->fg", weights**2, moments)
        ratio, law = noise_ratio_law(triangular_factor(weighted[:, support]),
                                     pooled[np.ix_(support, support)])
        residual = np.array([np.sum((theta[b * rows:(b + 1) * rows][:, support] @ law) ** 2)
                             for b in range(n_blocks)])
        noise = np.array([law @ moments[b][np.ix_(support, support)] @ law
                          for b in range(n_blocks)])
        weights = 1 / np.sqrt(np.maximum(noise, 1e-300))
        weights /= np.exp(np.mean(np.log(weights)))
    return weights, law, ratio, residual / noise


def main(path, system="half_car", out=None):
    record = {"file": path}
    data = dict(np.load(path))
    theta, moments, rows, mass, nonzero, n_blocks = prepared(data)
    features = [str(f) for f in data["features"]]
    if len(features) > data["theta"].shape[1]:  # unforced: the force columns are not fitted
        features = [f for f in features if not f.startswith("F[")]
    names = [features[j] for j in nonzero]
    truth = np.array([names.index(t) for t in TRUTH[system]])
    total = moments.sum(axis=0)
    r = triangular_factor(theta)

    def admissible(s):
        law = noise_ratio_law(r[:, s], total[np.ix_(s, s)])[1]
        return (explained_coordinates(theta[:, s], law, n_blocks).tolist(),
                definite_mass(data["mass_matrices"][:, nonzero][:, s], law))

    def cv(supports, how="x"):
        out = hg._scored(theta, moments, [np.asarray(s) for s in supports], how, n_blocks, 5,
                         rows)
        return out

    ratio_t, law_t = noise_ratio_law(r[:, truth], total[np.ix_(truth, truth)])
    c = cv([truth])[0]
    rows_b = theta.shape[0] // n_blocks
    own = [float(np.sum((theta[b * rows_b:(b + 1) * rows_b][:, truth] @ law_t) ** 2)
                 / (law_t @ moments[b][np.ix_(truth, truth)] @ law_t)) for b in range(n_blocks)]
    noise_share = [float(law_t @ moments[b][np.ix_(truth, truth)] @ law_t
                         / (law_t @ total[np.ix_(truth, truth)] @ law_t))
                   for b in range(n_blocks)]
    weights, _, ratio_bal, own_bal = block_balance(theta, moments, truth, n_blocks)
    record.update(truth_ratio=ratio_t, truth_cv=c.ratio, truth_cv_spread=c.spread,
                  truth_admissible=admissible(truth)[0] + [admissible(truth)[1]],
                  truth_block_ratios=own, truth_block_noise_share=noise_share,
                  balanced_weights=weights.tolist(), balanced_ratio=ratio_bal,
                  balanced_block_ratios=own_bal.tolist())
    print(f"truth's own ratio per block {np.round(own, 2).tolist()}, share of its noise per "
          f"block {np.round(noise_share, 5).tolist()}; noise-balanced blocks: weights "
          f"{np.round(weights, 3).tolist()}, ratio {ratio_bal:.3g}, per block "
          f"{np.round(own_bal, 2).tolist()}")
    print(f"{path}: {theta.shape[0]} rows, {theta.shape[1]} columns, {n_blocks} blocks")
    print(f"truth ({truth.size} terms): ratio all rows {ratio_t:.3g}, held out "
          f"{c.ratio:.3g} +- {c.spread:.2g}, admissible {admissible(truth)}")
    values, _ = noise_pencil(r, total)
    record["full_pencil"] = values[:6].tolist()
    print("full pencil, smallest ratios:", np.round(values[:8], 3).tolist())
    values_t, _ = noise_pencil(r[:, truth], total[np.ix_(truth, truth)])
    print("truth pencil, smallest ratios:", np.round(values_t[:5], 3).tolist())
    # column sizes and per-column noise
    sizes = np.sqrt(np.diag(total))
    print("truth columns' noise/size (scaled):",
          {names[j]: round(float(sizes[j]) / np.sqrt(theta.shape[0]), 4) for j in truth})
    print("truth law (scaled units):", {names[j]: round(float(v), 3) for j, v in
                                         zip(truth, law_t, strict=True)})
    order = law_elimination_path(r, total)
    inside = [k for k in range(2, len(order) + 1) if set(truth) <= set(order[:k].tolist())]
    first_out = min(inside) if inside else None
    print(f"backward path: truth inside supports of size >= {first_out}; ")
    record["backward_truth_inside_down_to"] = first_out
    for k in range(len(order), 1, -1):
        s = order[:k]
        lost = [names[j] for j in truth if j not in s]
        v = noise_ratio_law(r[:, s], total[np.ix_(s, s)])[0]
        if k <= (first_out or 99) + 1 and k >= (first_out or 0) - 3 or k <= 20:
            print(f"  size {k}: ratio {v:.3g}, removed next {names[order[k-1]]}, lacks {lost}")
    forward = law_forward_path(r, total)
    record["forward_positions"] = {names[j]: int(np.flatnonzero(forward == j)[0]) + 1
                                   for j in truth}
    print("forward path positions of true columns:",
          {names[j]: int(np.flatnonzero(forward == j)[0]) + 1 for j in truth})
    print("forward path first 20:", [names[j] for j in forward[:20]])
    bw = cv([order[:k] for k in range(2, len(order) + 1)], "backward")
    fw = cv([forward[:k] for k in range(2, len(forward) + 1)], "forward")
    for label, cands in (("backward", bw), ("forward", fw)):
        best = sorted(cands, key=lambda c: c.ratio)[:4]
        print(f"{label} best held out:", [(len(b.support), round(b.ratio, 3)) for b in best])
        record[f"{label}_best_cv"] = [(len(b.support), float(b.ratio)) for b in best]
    seen = set()
    starts = hg._admissible_starts(r, total, mass, seen)
    from pysindy_xl.optimizers.admissible import admissible_supports
    for s in admissible_supports(r, mass):
        lacks = [names[j] for j in truth if j not in s]
        extra = [names[j] for j in s if j not in truth]
        print(f"admissible start {len(s)} terms: lacks {lacks}; extra {extra}")
        record.setdefault("starts_lack", []).append(lacks)
    del starts
    law, ratio, sel = hg.select_law(theta, moments, n_blocks, mass_matrices=mass,
                                    noise_draws=rows.draws if rows is not None else None)
    chosen = np.flatnonzero(law)
    print(f"select_law: {len(chosen)} terms, ratio {ratio:.3g}, {sel.rule}, admissible "
          f"{sel.admissible}, held out {sel.cv_ratio[len(chosen)-1]:.3g}: "
          f"{[names[j] for j in chosen]}")
    record.update(chosen=[names[j] for j in chosen], chosen_admissible=bool(sel.admissible),
                  chosen_cv=float(sel.cv_ratio[len(chosen) - 1]))
    if out:
        import json
        with open(out, "a") as handle:
            handle.write(json.dumps(record, default=float) + "\n")


if __name__ == "__main__":
    main(*sys.argv[1:])
