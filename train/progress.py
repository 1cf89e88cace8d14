"""Progress bars whose rate and time left leave out the first item.

The first item of most of dwr-gym's work pays a start-up cost the others do not: the ``optimal``
controller plans every robot at its first step, a process pool starts, torch is imported. tqdm's
estimate from that first item alone predicts hours for work that ends in seconds. :class:`Progress`
shows the time left as unknown until a second item is done, then measures the rate from the end of
the first item on; the elapsed time stays the true one.
"""

from __future__ import annotations

from typing import Any

from tqdm.auto import tqdm


class Progress(tqdm):  # type: ignore[misc]
    """A ``tqdm`` bar whose rate, and so its time left, is measured from the end of the first item.

    ``fields`` are more keys for a ``bar_format`` (e.g. ``{label}``: tqdm's own ``{postfix}`` starts with a comma).
    """

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        self._after_first: tuple[float, float] | None = None  # (n, time) when the first item was done
        self.fields: dict[str, str] = dict(kwargs.pop("fields", None) or {})
        super().__init__(*args, **kwargs)

    def update(self, n: float | None = 1) -> bool | None:
        if self._after_first is None and n:
            displayed = super().update(n)
            self._after_first = (self.n, self._time())
            return displayed
        return super().update(n)

    @property
    def format_dict(self) -> dict[str, Any]:
        values = {**super().format_dict, **getattr(self, "fields", {})}
        if self.disable or "rate" not in values:
            return values
        rate = 0.0  # tqdm shows a rate of 0 as unknown ('?'), as it does the time left
        if self._after_first is not None:
            done, since = self.n - self._after_first[0], self._time() - self._after_first[1]
            rate = done / since if done > 0 and since > 0 else 0.0
        return {**values, "rate": rate}
