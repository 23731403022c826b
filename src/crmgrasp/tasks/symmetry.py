"""Mirror symmetries a task declares: which CRM is which CRM's mirror image, checked
against the contact model and the observation bins.

A learner may pool the experience of mirror-image histories (``symmetric=True``,
[`SymmetricAgent`][crmgrasp.agents.symmetric.SymmetricAgent]) only where the task states the
symmetry and [`check_symmetry`][] finds it consistent.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

from crmgrasp._validation import CrmgraspError
from crmgrasp.model.contact_model import ContactModel
from crmgrasp.model.sensing import Discretizer

__all__ = ["Symmetry", "symmetry_of", "check_symmetry"]


@dataclass(frozen=True)
class Symmetry:
    """A mirror symmetry of a task, declared by its author.

    Claim: some reflection of the plane maps the object onto itself and the start
    distribution onto itself (with the labels ``a`` and ``b`` swapped, which puts
    the palm back on the right). Then CRM ``(c, f, r)`` corresponds to
    ``(c', f', -r)`` (primes: swapped labels), ``rho`` and the error flag are
    unchanged and ``(m_a, m_b)`` becomes ``(-m_b, -m_a)``. ``actions[i]`` is the index
    of the CRM that corresponds to CRM ``i``; [`Task`][crmgrasp.tasks.Task] checks it against that
    rule and the observation bins (moments binned by magnitude, the same thresholds
    for both). Learners may use it to pool experience (``symmetric=True``).
    """

    actions: tuple[int, ...]


def symmetry_of(actions: Sequence[Any], mirror: Callable[[Any], Any]) -> Symmetry:
    """The [`Symmetry`][] that maps each CRM of ``actions`` to ``mirror(crm)`` (a contact
    model's ``mirror_crm``); an error naming the first CRM whose mirror the set lacks.

    >>> from crmgrasp.tasks import paper_box
    >>> symmetry_of(paper_box().actions, paper_box().model.mirror_crm)
    Symmetry(actions=(1, 0, 3, 2))
    """
    index = {a: i for i, a in enumerate(actions)}
    perm = []
    for a in actions:
        i = index.get(mirror(a))
        if i is None:
            raise CrmgraspError(f"the CRM set has no mirror of {a}; declare no symmetry")
        perm.append(i)
    return Symmetry(tuple(perm))


def check_symmetry(sym: Symmetry, actions: tuple[Any, ...], disc: Discretizer, model: ContactModel) -> None:
    """A one-line error unless ``sym`` is an involutive permutation of ``actions`` that maps each
    CRM to its mirror (``model.mirror_crm``) and ``disc`` bins the swapped moments by magnitude
    with the same thresholds; what [`Task`][crmgrasp.tasks.Task] checks where it is built."""
    perm = tuple(sym.actions)
    n = len(actions)
    if sorted(perm) != list(range(n)) or any(perm[perm[i]] != i for i in range(n)):
        raise CrmgraspError(f"symmetry actions must be an involutive permutation of 0..{n - 1}, got {perm!r}")
    for i, crm in enumerate(actions):
        m, expected = actions[perm[i]], model.mirror_crm(crm)
        if m != expected:
            raise CrmgraspError(f"symmetry maps {crm} to {m}, but its mirror is {expected}")
    axes, th = model.mirror_axes, disc.thresholds
    swapped = [(disc.names[i], disc.names[j]) for i, j in enumerate(axes) if i < j]
    if not disc.abs_moments or any(th[i] != th[j] for i, j in enumerate(axes)):
        same = ", ".join(f"{a} and {b}" for a, b in swapped)
        raise CrmgraspError(f"a symmetric task needs moments binned by magnitude with the same {same} thresholds")
