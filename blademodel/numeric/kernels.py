"""Choosing the kernel of a model: product modes or per-contact modes."""

from __future__ import annotations

from ..model import Model

#: Kernel names accepted by :func:`make_integrator` (and ``simulate(kernel=...)``).
KERNELS = ("auto", "product", "contact")


def choose_kernel(model: Model, kernel: str = "auto") -> str:
    """``"product"`` or ``"contact"`` for ``model``.

    ``auto`` takes the product-mode kernel for models with at most one contact
    (every mode written out and fused; the paper's pair runs there, unchanged) and
    the per-contact kernel for two or more contacts, where modes are never
    enumerated and rigid sticking is resolved jointly (the friction complementarity
    problem). ``product`` with several contacts is kept for comparison only: it
    decides transitions one guard at a time and can break Coulomb's law.
    """
    if kernel not in KERNELS:
        raise ValueError(f"kernel = {kernel!r} must be one of {', '.join(KERNELS)}")
    if kernel == "auto":
        return "product" if len(model.contacts) <= 1 else "contact"
    return kernel


def make_integrator(model: Model, *, kernel: str = "auto", detect_grazing: bool = True,
                    event_location: str | None = None, local_events: bool = True, **settings):
    """The integrator of ``model`` for ``kernel`` (see :func:`choose_kernel`).

    ``settings`` go to :class:`~blademodel.numeric.integrator.HybridIntegrator` or
    :class:`~blademodel.numeric.contact_kernel.ContactIntegrator`; ``detect_grazing``
    and ``local_events`` to the per-contact kernel only (the product kernel does not
    look for grazing, and its one contact makes the whole model one cluster);
    ``event_location`` (None: each kernel's default) to either.
    """
    if event_location is not None:
        settings["event_location"] = event_location
    if choose_kernel(model, kernel) == "product":
        from .integrator import HybridIntegrator
        return HybridIntegrator(model, **settings)
    from .contact_kernel import ContactIntegrator
    return ContactIntegrator(model, detect_grazing=detect_grazing, local_events=local_events, **settings)
