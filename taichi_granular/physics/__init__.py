"""Physics stages: each module holds pure per-particle/per-pair ``@ti.func``s and one short
``@ti.kernel`` per stage that loops over particles calling them."""
