"""The graph, described once, as data: topics, their schemas and QoS kind, the nodes, what each
node publishes and reads, and which inputs join into one of its ticks.

Launchers start the nodes and wait for the endpoints from here, every node takes its topics and
tick join from here, the tests' in-memory bus routes by it, and docs/GRAPH.md prints it
(``python -m homeo_msgs_py.graph``). Topic names are relative, so a namespace
(``--ros-args -r __ns:=/r1``) moves a whole graph.

Tick k of a node waits for each input at tick ``k + offset``. What a node needs of other topics rides
in the messages it reads (``Topic.carries``): the world and the observation of tick k carry the outcome
of tick k-1 (tick 0 has none), so the drives node wakes twice a tick (world, intention), the intention
and decision nodes once, and the critical path is the four hops world -> intention -> drives ->
decision -> world.
"""

from __future__ import annotations

from dataclasses import dataclass

# parameter ranges the nodes declare and the launchers check before anything starts
SEED_MAX = 2**31 - 1
TICKS_MAX = 10**9

STATE, EVENT = "state", "event"  # state topics are latched, events are not (qos.py)

# intention recognition: observe the true intention (the thesis's simulation) or recognise it
ORACLE, BAYES = "oracle", "bayes"
INTENTION_MODES = (ORACLE, BAYES)


@dataclass(frozen=True)
class Topic:
    name: str  # relative ROS name
    schema: str  # homeo_msgs_py.schemas
    kind: str  # STATE or EVENT
    # (key, offset) of another topic whose fields ride along, in a field of that key: the world of tick k
    # carries the outcome of k-1, so a node needing both wakes once for them (one delivery, not two)
    carries: tuple = ()


@dataclass(frozen=True)
class Input:
    topic: str  # key of TOPICS
    offset: int = 0  # tick k reads this input of tick k + offset
    learning_only: bool = False  # read only when the intention node learns (bayes mode)


@dataclass(frozen=True)
class NodeDesc:
    name: str
    module: str  # run as ``python -m MODULE``
    role: str  # world | intention | drives | decision
    publishes: tuple  # keys of TOPICS
    inputs: tuple  # of Input
    services: tuple = ()  # relative to the node (~/...)
    joins: bool = True  # its inputs join into ticks (the world node paces the ticks itself)
    external: tuple = ()  # keys of TOPICS it may read from outside the graph (a person), when its world asks
    executable: str = ""  # its console script: ``ros2 run homeo_robot EXECUTABLE``, ``ros2 launch`` (pyproject.toml)

    def reads(self, learning: bool) -> tuple:
        return tuple(i for i in self.inputs if learning or not i.learning_only)

    def join_offsets(self, learning: bool) -> dict:
        """``TickJoin`` offsets of this node: input topic key -> offset."""
        return {i.topic: i.offset for i in self.reads(learning)}


TOPICS: dict[str, Topic] = {
    "world": Topic("homeo/world", "homeo/world", STATE, carries=(("outcome", -1),)),
    "observation": Topic("homeo/observation", "homeo/observation", EVENT, carries=(("outcome", -1),)),
    "intention": Topic("homeo/intention", "homeo/intention", STATE),
    "drives": Topic("homeo/drives", "homeo/drives", STATE),
    "action": Topic("homeo/action", "homeo/action", EVENT),
    # read by no node of the graph (it rides in world and observation of the next tick): for people,
    # recordings and replay
    "outcome": Topic("homeo/outcome", "homeo/outcome", EVENT),
    "run_status": Topic("homeo/run_status", "homeo/run_status", STATE),
    # what a robot asks of the devices around it (a player to play, a light to switch): for whoever
    # drives them; no node of the graph reads it
    "device": Topic("homeo/device", "homeo/device", EVENT),
    # the action the robot is performing, latched: a person in the loop reads it whenever they look
    # (``homeo/action`` is an event of the lockstep: gone for a reader that comes late)
    "last_action": Topic("homeo/last_action", "homeo/last_action", STATE),
    # a person playing the human (``--human person``): read by the simulation in that mode only
    "human_input": Topic("homeo/human_input", "homeo/human_input", EVENT),
}
# the graph's own topics, signed when the graph runs with authentication (auth.py); a person's
# input is typed by hand and is not
SIGNED = frozenset(k for k in TOPICS if k != "human_input")
DIAGNOSTICS = "/diagnostics"  # absolute: every node reports to the one aggregator topic

WORLD = "homeo_world"  # the one world node: any environment (simulation, Pepper, ...) behind the boundary
NODES: dict[str, NodeDesc] = {
    WORLD: NodeDesc(WORLD, "homeo_decision.world_node", "world",
                    ("world", "observation", "outcome", "run_status", "device", "last_action"), (Input("action"),),
                    ("~/reset",),
                    joins=False, external=("human_input",), executable="homeo-world-node"),
    "homeo_intention": NodeDesc("homeo_intention", "homeo_intention.node", "intention", ("intention",),
                                (Input("observation"),), ("~/save_model", "~/load_model"),
                                executable="homeo-intention-node"),
    "homeo_drives": NodeDesc("homeo_drives", "homeo_decision.drives_node", "drives", ("drives",),
                             (Input("world"), Input("intention")), executable="homeo-drives-node"),
    "homeo_decision": NodeDesc("homeo_decision", "homeo_decision.node", "decision", ("action",),
                               (Input("drives"),), ("~/save_q", "~/load_q", "~/reset"), executable="homeo-decision-node"),
}
LAUNCHER = "homeo_launch"  # the launcher's own node (its monitor)
RECORDER = "homeo_record"  # the launcher's tap (a bag, a live view)
ROBOT_NODES = ("homeo_intention", "homeo_drives", "homeo_decision")
GRAPH = (WORLD,) + ROBOT_NODES  # every robot, simulated or real, runs this graph


def topic_name(key: str) -> str:
    return TOPICS[key].name


def key_of(name: str) -> str | None:
    """The key of a topic given by its name, with or without the leading slash and a namespace
    (``/r1/homeo/world``); None: not ours."""
    bare = name.lstrip("/")
    return next((k for k, t in TOPICS.items() if bare == t.name or bare.endswith("/" + t.name)), None)


def schema_of(key: str) -> str:
    try:
        return TOPICS[key].schema
    except KeyError:
        raise KeyError(f"{key} is not a homeo topic; known: {', '.join(TOPICS)}") from None


def endpoints(learning: bool) -> dict[str, tuple[int, int]]:
    """(writers, readers) of every topic the graph's nodes publish or join (the launcher waits for all)."""
    out: dict[str, list] = {}
    for n in GRAPH:
        node = NODES[n]
        for t in node.publishes:
            if t != "run_status":  # read by the launcher, not by a node
                out.setdefault(t, [0, 0])[0] += 1
        for i in node.reads(learning):
            out.setdefault(i.topic, [0, 0])[1] += 1
    return {t: (w, r) for t, (w, r) in out.items()}


def readers(topic: str, learning: bool) -> int:
    """How many nodes of the graph read ``topic`` (the world node's start gate waits for them)."""
    return endpoints(learning).get(topic, (0, 0))[1]


def max_readers(topic: str) -> int:
    """The most nodes of the graph reading ``topic`` in either mode (0: none reads it)."""
    return max(readers(topic, learning) for learning in (False, True))


def min_readers(topic: str) -> int:
    """The fewest nodes reading ``topic`` in either mode: a robot node, which does not know whether
    the intention node learns, waits for that many readers (and the launcher's tap) before it publishes."""
    return min(readers(topic, learning) for learning in (False, True))


def own_endpoints(infos, nodes, namespace: str) -> int:
    """How many of the endpoints ``infos`` (rclpy ``TopicEndpointInfo``: node_name, node_namespace)
    belong to ``nodes`` in ``namespace``: a start gate counts its own graph, not whoever else
    listens on the domain."""
    return sum(1 for i in infos if i.node_name in nodes and i.node_namespace == namespace)


def describe() -> str:
    """The graph as a markdown table (docs/GRAPH.md)."""
    lines = ["| node | role | publishes | reads (tick offset) | services |", "|---|---|---|---|---|"]
    for n in NODES.values():
        reads = ", ".join(f"{TOPICS[i.topic].name} ({i.offset:+d}" + "".join(
            f", with {TOPICS[k].name} ({i.offset + off:+d})" for k, off in TOPICS[i.topic].carries) + ")"
                          + (" bayes only" if i.learning_only else "") for i in n.inputs)
        lines.append(f"| {n.name} | {n.role} | {', '.join(TOPICS[t].name for t in n.publishes)} | {reads} | "
                     f"{', '.join(n.services) or '-'} |")
    lines += ["", "| topic | schema | kind | carries |", "|---|---|---|---|"]
    lines += [f"| {t.name} | {t.schema} | {t.kind} | "
              f"{', '.join(f'{TOPICS[k].name} ({o:+d})' for k, o in t.carries) or '-'} |" for t in TOPICS.values()]
    return "\n".join(lines)


if __name__ == "__main__":
    print(describe())
