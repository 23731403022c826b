"""Learners and baselines sharing one interface (:class:`~crmgrasp.agents.base.Agent`)."""

from .base import Agent, greedy_choice
from .baselines import FixedSequence, RandomAgent
from .lockstep import train_trials_lockstep
from .policy import GreedyPolicy
from .tabular import DynaQ, QLearning, Sarsa, SarsaLambda, TabularAgent
from .training import AGENTS, encoder_for, episodes_to_within, evaluate, make_agent, run_episode, train_trials

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
