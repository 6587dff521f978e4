"""QoS profiles of the contract (ARCHITECTURE.md: state latched, events reliable and volatile)."""

from __future__ import annotations

from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

from .graph import STATE, TOPICS

# State: the newest value is what matters, and a late joiner gets it (latched).
STATE_PUB = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=1, reliability=ReliabilityPolicy.RELIABLE,
                       durability=DurabilityPolicy.TRANSIENT_LOCAL)
# Readers keep many: a burst of garbage on the topic (a stranger's, thousands of messages) must
# not push out the real message before the executor takes it; the memory is used only while a
# burst lasts. Depth does not affect QoS compatibility. A message lost anyway costs one timeout:
# the world sends the tick again (lockstep.py).
SUB_DEPTH = 1000
STATE_SUB = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=SUB_DEPTH, reliability=ReliabilityPolicy.RELIABLE,
                       durability=DurabilityPolicy.TRANSIENT_LOCAL)
EVENT = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=50, reliability=ReliabilityPolicy.RELIABLE,
                   durability=DurabilityPolicy.VOLATILE)
EVENT_SUB = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=SUB_DEPTH, reliability=ReliabilityPolicy.RELIABLE,
                       durability=DurabilityPolicy.VOLATILE)


def pub_qos(key: str) -> QoSProfile:
    """The writer QoS of topic ``key`` (of ``graph.TOPICS``)."""
    return STATE_PUB if TOPICS[key].kind == STATE else EVENT


def sub_qos(key: str) -> QoSProfile:
    return STATE_SUB if TOPICS[key].kind == STATE else EVENT_SUB


def quiet_pub_events():
    """No QoS-event handlers on a writer. rclpy adds two per endpoint by default (incompatible
    QoS / type warnings), and every handler is re-added to the wait set on every spin: about a
    third of a node's time per tick (measured with cProfile). The graph checks matching itself
    (the simulation waits for its readers and names what is missing)."""
    from rclpy.event_handler import PublisherEventCallbacks

    return PublisherEventCallbacks(use_default_callbacks=False)


def quiet_sub_events():
    """As ``quiet_pub_events``, for a reader."""
    from rclpy.event_handler import SubscriptionEventCallbacks

    return SubscriptionEventCallbacks(use_default_callbacks=False)


def dds_defaults(env=None) -> dict:
    """DDS settings of the project, each unless the user set it: discovery on this machine only,
    and Fast DDS's built-in transports limited to UDP. With discovery on this machine only,
    rmw_fastrtps (Jazzy) sets its own transports, shared memory and UDP on loopback, and the
    second setting has no effect (seen: ``dds.shm.*`` threads in every node); it applies when
    the user widens the range (ROS_AUTOMATIC_DISCOVERY_RANGE=SUBNET)."""
    import os

    env = os.environ if env is None else env
    return {k: env.get(k, v) for k, v in (("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST"),
                                          ("FASTDDS_BUILTIN_TRANSPORTS", "UDPv4"))}
