"""What the dribbling commands print and draw: the greedy metrics of a report, and the reliability figure (the
paper's Figs. 9-10)."""

from __future__ import annotations

from typing import Any


def print_dribble_report(report: Any, title: str) -> None:
    import numpy as np

    print(title)
    print(f"  mean distance      {report.mean_distance:8.2f} m")
    print(f"  median distance    {float(np.median(report.distances)):8.2f} m")
    print(f"  share >= 20 m      {100 * report.share_reaching(20):8.1f} %")
    print(f"  ball-loss rate     {100 * report.loss_rate:8.1f} %   (the others kept it to the action limit)")


def reliability_figure(report: Any, title: str) -> Any:
    """A matplotlib figure (Agg) of a reliability test: where the players that lost the ball lost it, and the share of
    players reaching each distance. The caller saves and closes it."""
    import matplotlib
    import numpy as np

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    lost = report.distances[report.ball_lost]
    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4))
    top = max(1.0, float(np.ceil(report.distances.max())))
    bins = np.arange(0.0, top + 1.0, 1.0)
    left.hist(lost, bins=bins, color="tab:red", edgecolor="black", linewidth=0.4)
    left.set(
        xlabel="metres dribbled before losing the ball",
        ylabel="players",
        title=f"Ball lost: {len(lost)} of {len(report.distances)} players",
    )
    metres = np.linspace(0.0, top, 400)
    share = (report.distances[None, :] >= metres[:, None]).mean(1) * 100
    right.plot(metres, share, color="tab:blue")
    right.set(
        xlabel="metres", ylabel="% of players reaching it", title="Cumulative share reaching each distance", ylim=(0, 101)
    )
    right.grid(alpha=0.3)
    fig.suptitle(title)
    fig.tight_layout()
    return fig
