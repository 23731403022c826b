"""Learners and baselines sharing one interface ([`Agent`][crmgrasp.agents.base.Agent])."""

from crmgrasp.agents.base import Agent, greedy_choice
from crmgrasp.agents.baselines import FixedSequence, RandomAgent
from crmgrasp.agents.lockstep import train_trials_lockstep
from crmgrasp.agents.policy import GreedyPolicy
from crmgrasp.agents.tabular import DynaQ, QLearning, Sarsa, SarsaLambda, TabularAgent
from crmgrasp.agents.training import (
    AGENTS,
    encoder_for,
    episodes_to_within,
    evaluate,
    make_agent,
    run_episode,
    train_trials,
)

__all__ = [
    "Agent",
    "greedy_choice",
    "FixedSequence",
    "RandomAgent",
    "GreedyPolicy",
    "DynaQ",
    "QLearning",
    "Sarsa",
    "SarsaLambda",
    "TabularAgent",
    "AGENTS",
    "encoder_for",
    "episodes_to_within",
    "evaluate",
    "make_agent",
    "run_episode",
    "train_trials",
    "train_trials_lockstep",
]
