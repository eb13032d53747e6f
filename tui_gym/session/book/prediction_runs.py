"""Run figures of prediction: learners of V on the random walk, scored by RMS error per episode."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from tui_gym.algorithms import Predictor, algorithm
from tui_gym.algorithms.prediction import rms_curve
from tui_gym.core.engine.loop import ModelArrays
from tui_gym.games import game_named
from tui_gym.games.base import TrainingModel
from tui_gym.session.book.figure import BookFigure, FigureOptions, FigureStopped, Progress
from tui_gym.session.book.runs import Learner, Played, counts

__all__ = ["play_prediction"]


def play_prediction(figure: BookFigure, states: int, learners: Sequence[Learner],
                    options: FigureOptions, progress: Progress) -> list[Played]:
    """Every learner's RMS curves over the figure's runs (see the module docstring)."""
    runs, episodes = counts(figure, options)
    game = game_named("random-walk")
    found = game.training_model(game.normalize_kwargs({"states": states}))
    assert isinstance(found, TrainingModel)
    model = ModelArrays.of(found.model)
    about = f"{runs} runs × {episodes} episodes of {len(learners)} learners"
    played = []
    for index, learner in enumerate(learners):
        progress(index, len(learners), about)
        cls = algorithm(learner.algorithm)
        assert issubclass(cls, Predictor)
        values = np.empty((runs, episodes))
        settings = cls.settings(learner.settings)
        truth = None
        for run in range(runs):
            if options.stop is not None and options.stop.is_set():
                raise FigureStopped(f"Figure {figure.name} stopped")
            agent = cls(found.model.n_actions, settings, n_states=found.model.n_states,
                        seed=options.seed + run)
            truth = truth or agent.truth(found.model)  # one policy: the random one
            values[run] = rms_curve(agent, model, truth, episodes)
        played.append(Played(learner.label, values, None, None))
    progress(len(learners), len(learners), about)
    return played
