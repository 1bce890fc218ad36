"""The place-recognition benchmark: a dataset of two traversals of one route under two
lightings (:func:`~.dataset.generate_vpr`, spec :class:`~.spec.VprSpec`, shipped protocols in
``data/``) and recall@N of any descriptors on it (:func:`~.score.evaluate_vpr`)."""

from marsscene._lazy import lazy_attributes

__all__ = ["BASELINES", "VprSpec", "evaluate_vpr", "generate_vpr"]

__getattr__ = lazy_attributes(__name__, {
    "VprSpec": "marsscene.benchmark.vpr.spec", "generate_vpr": "marsscene.benchmark.vpr.dataset",
    "BASELINES": "marsscene.benchmark.vpr.score", "evaluate_vpr": "marsscene.benchmark.vpr.score",
})
