"""What an export could not render as set, gathered into one warning for the render report.

Two kinds of entries: whole things left out, counted and named by kind (`leave_out("surface object",
name)` for Plane and Suzanne gives "2 surface objects (Plane, Suzanne)"), and settings rendered otherwise
than set ("material 'Fog' ▸ Volume Scatter: phase Mie rendered as Henyey–Greenstein (g = 0.3)").
Nothing the exporter does not render is skipped silently.
"""

from dataclasses import dataclass, field

MAX_NAMES = 6  # names listed per kind before "…"


@dataclass
class Notes:
    left_out: dict = field(default_factory=dict)  # (kind, plural) → names
    approximations: list = field(default_factory=list)

    def leave_out(self, kind: str, name: str, plural: str | None = None) -> None:
        """Name `name` as a `kind` (a singular noun; `plural` when adding "s" is not it) not rendered."""
        names = self.left_out.setdefault((kind, plural or kind + "s"), [])
        if name not in names:
            names.append(name)

    def add(self, text: str) -> None:
        if text not in self.approximations:
            self.approximations.append(text)

    def warning(self) -> str | None:
        """The one warning naming everything, or None when everything renders as set."""
        parts = []
        for (kind, plural), names in self.left_out.items():
            shown = ", ".join(names[:MAX_NAMES]) + (", …" if len(names) > MAX_NAMES else "")
            parts.append(f"{len(names)} {kind if len(names) == 1 else plural} ({shown})")
        rendered = ("not rendered: " + "; ".join(parts)) if parts else ""
        approximations = "; ".join(self.approximations)
        if rendered and approximations:
            return f"{rendered}; {approximations}"
        return rendered or approximations or None
