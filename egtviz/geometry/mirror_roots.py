r"""Where a line through a mirror's focus meets the mirror's quadric: both roots.

In the mirror frame (``docs/conventions.md``) the line :math:`\lambda v`
through the focus meets

- the hyperboloid :math:`(z + e)^2 / a^2 - (x^2 + y^2) / b^2 = 1`,
  :math:`e = \sqrt{a^2 + b^2}`, where
  :math:`\lambda^2 (b^2 v_z^2 - a^2 \rho^2) + 2 e b^2 v_z \lambda + b^4 = 0`
  (:math:`\rho^2 = v_x^2 + v_y^2`), i.e.

  .. math:: \lambda_{1,2} = \frac{b^2 (-e v_z \pm a |v|)}{b^2 v_z^2 - a^2 \rho^2}

  (one root, :math:`-b^2 / (2 e v_z)`, when the denominator vanishes: the line
  is parallel to an asymptote);
- the paraboloid :math:`z = (x^2 + y^2 - h^2) / (2h)`, where
  :math:`\rho^2 \lambda^2 - 2 h v_z \lambda - h^2 = 0`, i.e.
  :math:`\lambda_{1,2} = h (v_z \pm |v|) / \rho^2`.

These are the algebraic intersections, on either sheet and on either side of
the focus; which one a camera sees is
:meth:`~egtviz.geometry.mirrors.HyperbolicMirror.intersect`'s business.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from ._validate import GeometryError, as_points, as_positive

__all__ = ["line_quadric_roots"]


def line_quadric_roots(v: npt.ArrayLike, a: float, b: float | None = None) -> tuple[np.ndarray, np.ndarray]:
    r"""Both roots :math:`(\lambda_1, \lambda_2)` of the line :math:`\lambda v` with a mirror quadric.

    Args:
        v: (N, 3) directions in the mirror frame.
        a: hyperbola parameter ``a``, or the parabola's ``h`` when ``b`` is None.
        b: hyperbola parameter ``b``; ``None`` for a parabolic mirror.

    Returns:
        ``(lambda1, lambda2)``, each (N,): the ``+`` and ``-`` roots of the
        module docstring; equal where there is one root; NaN where there is
        none. A parabola's axis (:math:`\rho = 0`) meets it once, at the apex:
        both are then :math:`-h / (2 v_z)`.

    Raises:
        GeometryError: bad shapes, non-positive parameters, a zero direction.
    """
    d = as_points(v, "v", 3)
    if np.any(np.linalg.norm(d, axis=1) == 0.0):
        raise GeometryError("v: a direction is zero")
    x, y, z = d.T
    rho2 = x * x + y * y
    norm = np.linalg.norm(d, axis=1)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        if b is None:
            h = as_positive(a, "a")
            l1 = h * (z + norm) / rho2
            l2 = h * (z - norm) / rho2
            axis = rho2 <= 1e-24 * norm * norm
            single = -h / (2.0 * z)
            return np.where(axis, single, l1), np.where(axis, single, l2)
        a = as_positive(a, "a")
        b = as_positive(b, "b")
        e = np.hypot(a, b)
        den = b * b * z * z - a * a * rho2
        l1 = b * b * (-e * z + a * norm) / den
        l2 = b * b * (-e * z - a * norm) / den
        parallel = np.abs(den) <= 1e-12 * (b * b * z * z + a * a * rho2)
        single = -b * b / (2.0 * e * z)
    return np.where(parallel, single, l1), np.where(parallel, single, l2)
