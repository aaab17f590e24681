"""Sparse representation classification (SRC), as in seed paper 003.

The training samples, each scaled to unit Euclidean norm, are the columns of a dictionary
``A = [A_1 ... A_K]`` (``A_k``: the samples of class ``k``). A test sample ``y`` is coded by
orthogonal matching pursuit with at most ``sparsity`` atoms (paper: 5),

    x = argmin ||A x - y||_2  subject to  ||x||_0 <= sparsity,

and assigned to the class with the smallest class residual ``||y - A_k x_k||_2`` (``x_k``:
the coefficients of class ``k``'s atoms). OMP is scikit-learn's ``orthogonal_mp``.
"""

from __future__ import annotations

import numpy as np
from sklearn.base import BaseEstimator, ClassifierMixin
from sklearn.linear_model import orthogonal_mp
from sklearn.utils.multiclass import check_classification_targets
from sklearn.utils.validation import check_is_fitted, validate_data

from .._validate import check_classes, integer
from ..errors import ConfigError


class SRCClassifier(ClassifierMixin, BaseEstimator):
    """SRC with OMP.

    Parameters:
        sparsity: largest number of training samples in a code (paper 003: 5); capped at the
            numbers of training samples and of features.
        normalize: scale each training sample (and each test sample) to unit norm.

    Learned state: ``classes_``, ``dictionary_`` ``(n_features, n_train)`` (unit-norm
    columns), ``atom_class_`` (class index of each column), ``n_features_in_``. Errors
    (NaN, mismatched lengths, wrong feature count) are :class:`ConfigError` (a ValueError).
    """

    def __init__(self, sparsity: int = 5, normalize: bool = True) -> None:
        self.sparsity = sparsity
        self.normalize = normalize

    @staticmethod
    def _unit(x: np.ndarray) -> np.ndarray:
        norm = np.linalg.norm(x, axis=1, keepdims=True)
        return x / np.where(norm > 0, norm, 1.0)

    def fit(self, X: object, y: object) -> SRCClassifier:
        integer("sparsity", self.sparsity, 1, None)
        try:
            x, y_arr = validate_data(self, X, y, dtype=np.float64)
            check_classification_targets(y_arr)
        except ValueError as exc:
            raise ConfigError(f"SRCClassifier.fit: {exc}") from None
        self.classes_ = check_classes(y_arr)
        atoms = self._unit(x) if self.normalize else x
        self.dictionary_ = np.ascontiguousarray(atoms.T)
        self.atom_class_ = np.searchsorted(self.classes_, y_arr)
        return self

    def _check_X(self, X: object) -> np.ndarray:
        check_is_fitted(self, "dictionary_")
        try:
            x = validate_data(self, X, dtype=np.float64, reset=False)
        except ValueError as exc:
            raise ConfigError(f"SRCClassifier: {exc}") from None
        return self._unit(x) if self.normalize else x

    def codes(self, X: object) -> np.ndarray:
        """Sparse codes ``(samples, n_train)`` of ``X`` over the training dictionary."""
        x = self._check_X(X)
        n_atoms = min(int(self.sparsity), self.dictionary_.shape[1], x.shape[1])
        code = orthogonal_mp(self.dictionary_, x.T, n_nonzero_coefs=n_atoms)
        return np.asarray(code).reshape(self.dictionary_.shape[1], -1).T

    def residuals(self, X: object) -> np.ndarray:
        """Class residuals ``||y - A_k x_k||_2``, shape ``(samples, classes)``."""
        code = self.codes(X)
        x = self._check_X(X)
        out = np.empty((x.shape[0], len(self.classes_)))
        for k in range(len(self.classes_)):
            mask = self.atom_class_ == k
            recon = code[:, mask] @ self.dictionary_[:, mask].T
            out[:, k] = np.linalg.norm(x - recon, axis=1)
        return out

    def decision_function(self, X: object) -> np.ndarray:
        """Negative class residuals, ``(samples, classes)`` (larger is more likely); for two
        classes ``(samples,)``: residual of class 0 minus residual of class 1 (> 0 favours
        ``classes_[1]``), as scikit-learn expects."""
        res = self.residuals(X)
        return res[:, 0] - res[:, 1] if res.shape[1] == 2 else -res

    def predict(self, X: object) -> np.ndarray:
        res = self.residuals(X)
        return self.classes_[np.argmin(res, axis=1)]
