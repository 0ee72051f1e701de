"""The process of one job (sweep/engine.py): reads ``{"entry": "module:function", "payload": {...}}``
on stdin, calls the function with the payload and prints its result on one line after
``RESULT_PREFIX``; an exception becomes a failed result naming it (its traceback on stderr)."""
import importlib
import json
import sys
import traceback

from .engine import RESULT_PREFIX, failed


def main() -> int:
    job = json.loads(sys.stdin.read())
    module, _, function = job["entry"].partition(":")
    try:
        result = {"status": "ok", **getattr(importlib.import_module(module), function)(job["payload"])}
    except Exception as err:  # noqa: BLE001 - the run's failure is its result
        traceback.print_exc()
        result = failed(f"{type(err).__name__}: {err}")
    print("\n" + RESULT_PREFIX + json.dumps(result), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
