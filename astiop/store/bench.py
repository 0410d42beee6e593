"""Benchmark runs and their per-case results."""

from __future__ import annotations

import json
import time
from typing import Any

from astiop.store.connection import Connection, row_id


class BenchTables(Connection):
    # -- benchmark runs ----------------------------------------------------------------
    def create_bench_run(self, stage: int, config: dict[str, Any]) -> int:
        with self._tx():
            row = self.db.table("bench_runs").insert(
                {
                    "started_at": time.time(),
                    "stage": stage,
                    "models": json.dumps(config["models"]),
                    "modes": json.dumps(config["modes"]),
                    "seed": config["seed"],
                    "case_limit": config["limit"],
                    "status": "running",
                    "config": json.dumps(config),
                }
            )
        return row_id(row.last_pk)

    def bench_run(self, run_id: int) -> dict[str, Any] | None:
        rows = list(self.db.query("SELECT * FROM bench_runs WHERE id = ?", [run_id]))
        return rows[0] if rows else None

    def bench_runs(self) -> list[dict[str, Any]]:
        return list(
            self.db.query(
                "SELECT r.*, (SELECT count(*) FROM bench_results b WHERE b.run_id = r.id) "
                "AS results FROM bench_runs r ORDER BY r.id DESC"
            )
        )

    def bench_results(self, run_id: int) -> list[dict[str, Any]]:
        return list(
            self.db.query("SELECT * FROM bench_results WHERE run_id = ? ORDER BY id", [run_id])
        )

    def add_bench_result(self, run_id: int, row: dict[str, Any]) -> None:
        with self._tx():
            self.db.table("bench_results").insert(
                {"run_id": run_id, **row, "created_at": time.time()}, replace=True
            )

    def end_bench_run(self, run_id: int, status: str) -> None:
        """done or interrupted; an interrupted run keeps its results and can resume."""
        with self._tx():
            self.db.table("bench_runs").update(
                run_id, {"status": status, "finished_at": time.time()}
            )
