"""Running totals over the journal, for the metrics a site's Prometheus scrapes: commands by
verdict, model turns by outcome (time and tokens), open alerts."""

from __future__ import annotations

from astiop.store.connection import Connection

# a command's verdict, from its row: refused by validation or safety, run, or valid and not run
# (the operator declined it, the E-STOP held it, a turn ended first)
VERDICT_SQL = (
    "CASE WHEN valid = 0 THEN 'refused' WHEN executed = 1 THEN 'executed' ELSE 'not_executed' END"
)


class TallyTables(Connection):
    def command_verdicts(self) -> dict[str, int]:
        """How many commands each verdict has had, over the whole journal."""
        rows = self.db.conn.execute(
            f"SELECT {VERDICT_SQL} AS verdict, COUNT(*) FROM commands GROUP BY verdict"
        )
        return {verdict: count for verdict, count in rows}

    def turn_totals(self) -> list[dict]:
        """Per model and status: turns, their seconds, and prompt and completion tokens (only
        finished turns have seconds)."""
        rows = self.db.conn.execute(
            "SELECT model, status, COUNT(*), COALESCE(SUM(total_s), 0), "
            "COUNT(total_s), COALESCE(SUM(prompt_tokens), 0), "
            "COALESCE(SUM(completion_tokens), 0) FROM interactions GROUP BY model, status"
        )
        keys = ("model", "status", "turns", "seconds", "timed", "prompt", "completion")
        return [dict(zip(keys, row, strict=True)) for row in rows]

    def open_alert_counts(self) -> dict[tuple[str, str], int]:
        """Alerts not acknowledged, per (robot, kind)."""
        rows = self.db.conn.execute(
            "SELECT robot, kind, COUNT(*) FROM alerts WHERE acknowledged_at IS NULL "
            "GROUP BY robot, kind"
        )
        return {(robot, kind): count for robot, kind, count in rows}
