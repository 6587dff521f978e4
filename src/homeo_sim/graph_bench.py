"""``homeo-launch bench``: the graph's seconds per tick against the floor of rclpy itself.

The floor is a ring of as many processes as the tick's critical path has hops (world ->
intention -> drives -> decision -> world: 4), each passing a message on with an empty
callback. Both run in the same invocation, one after the other, on the same machine.
"""

from __future__ import annotations

import json
import time

from .launch import GraphError, SimOptions, run_graph
from .processes import Graph, NodeSpec, graph_env

HOPS = 4


def floor_s_per_tick(iterations: int, hops: int = HOPS, bound_s: float = 120.0) -> float:
    specs = [NodeSpec(f"homeo_floor_{i}", "homeo_msgs_py.floor_chain",
                      {"index": i, "hops": hops, "iterations": iterations}, args=[]) for i in range(hops)]
    # every process declares node name homeo_floor; give each its own through the params file key
    for s in specs:
        s.args = ["--ros-args", "-r", f"__node:={s.name}"]
    graph = Graph(specs, graph_env())
    try:
        graph.start()
        end = time.monotonic() + bound_s
        head = graph.procs[specs[0].name]
        while head.poll() is None:
            dead = graph.dead()
            if dead and dead[0] != specs[0].name:
                raise GraphError(f"floor process {dead[0]} exited with code {dead[1]}: {graph.log_tail(dead[0])}")
            if time.monotonic() > end:
                raise GraphError(f"the floor chain did not finish within {bound_s:g} s")
            time.sleep(0.05)
        for line in graph.log_tail(specs[0].name, 50).splitlines():
            if line.startswith("{"):
                return json.loads(line)["s_per_tick"]
        raise GraphError(f"the floor chain printed no result: {graph.log_tail(specs[0].name)}")
    finally:
        graph.stop()
        graph.close()


def cmd_bench(args) -> int:
    st = run_graph(SimOptions(iterations=args.iterations), quiet=True)
    graph = st["elapsed_s"] / args.iterations
    floor = floor_s_per_tick(args.iterations)
    out = {"graph_s_per_tick": graph, "floor_s_per_tick": floor, "ratio": graph / floor, "rss_mb": st["rss_mb"]}
    if args.json:
        print(json.dumps(out))
    else:
        print(f"graph, lockstep        : {graph * 1e3:7.3f} ms/tick ({args.iterations} ticks, {st['missed']} missed)")
        print(f"floor, {HOPS} rclpy hops   : {floor * 1e3:7.3f} ms/tick")
        print(f"ratio graph / floor    : {out['ratio']:7.2f}  (target <= 2)")
        print(f"graph resident memory  : {st['rss_mb']:7.0f} MiB (4 node processes)")
    return 0
