"""A DataTable for a few values updated in place, every second or so (topic rates and ages)."""

from __future__ import annotations

from textual.cache import LRUCache
from textual.widgets import DataTable


class LiveTable(DataTable):
    """Renders a body cell again only when its value changes. The stock table renders every cell
    again after any `update_cell` (its caches key on an update count): for a dozen numbers a
    second, that was a third of an idle Dashboard's CPU. Its private `_render_cell` is wrapped:
    Textual is pinned exactly (pyproject), and the snapshots would show a change of it."""

    def __init__(self, *args, **kwargs):
        self._by_cell: LRUCache[tuple, tuple[object, list]] = LRUCache(4096)
        super().__init__(*args, **kwargs)

    def _render_cell(
        self,
        row_index: int,
        column_index: int,
        base_style,
        width: int,
        cursor: bool = False,
        hover: bool = False,
    ):
        args = (row_index, column_index, base_style, width, cursor, hover)
        if row_index < 0 or column_index < 0:  # the header, row labels: as the stock table
            return super()._render_cell(*args)
        row_key = self._row_locations.get_key(row_index)
        column_key = self._column_locations.get_key(column_index)
        value = self._data[row_key][column_key]
        key = (row_key, column_key, *args, self._show_hover_cursor, self._pseudo_class_state)
        key += (self.rows[row_key].height,)
        hit = self._by_cell.get(key)
        if hit is not None and hit[0] is value:
            return hit[1]
        lines = super()._render_cell(*args)
        self._by_cell[key] = (value, lines)
        return lines

    def _clear_caches(self) -> None:  # a style, the cursor, the stripes: every cell again
        super()._clear_caches()
        self._by_cell.clear()

    def notify_style_update(self) -> None:  # the theme
        super().notify_style_update()
        self._by_cell.clear()
