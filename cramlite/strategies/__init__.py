"""Ordering strategies: which item to fetch next. Pure Python/numpy, no PyBullet."""

from cramlite.strategies.base import Strategy, StrategyCrashed, StrategyError
from cramlite.strategies.batch import (
    MAX_OPTIMAL_BATCH_ITEMS,
    NearestBatchStrategy,
    OPMBatchStrategy,
    OptimalBatchStrategy,
    RandomBatchStrategy,
)
from cramlite.strategies.candidates import CATEGORIES, Candidate, OPMParams
from cramlite.strategies.cost import DIMS, FORMS, CostModel, span_weights
from cramlite.strategies.opm import NearestStrategy, OPMStrategy, OPMTwoStepStrategy
from cramlite.strategies.optimal import MAX_OPTIMAL_ITEMS, OptimalStrategy
from cramlite.strategies.registry import available_strategies, make_strategy, strategy_class
from cramlite.strategies.simple import BaselineStrategy, RandomStrategy

__all__ = ["CATEGORIES", "DIMS", "FORMS", "MAX_OPTIMAL_BATCH_ITEMS", "MAX_OPTIMAL_ITEMS",
           "BaselineStrategy", "Candidate", "CostModel", "NearestBatchStrategy",
           "NearestStrategy", "OPMBatchStrategy", "OPMParams", "OPMStrategy",
           "OPMTwoStepStrategy", "OptimalBatchStrategy", "OptimalStrategy",
           "RandomBatchStrategy", "RandomStrategy", "Strategy", "StrategyCrashed", "StrategyError",
           "available_strategies", "make_strategy", "span_weights", "strategy_class"]
