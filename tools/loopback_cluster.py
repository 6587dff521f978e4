"""A Ray cluster on this machine's loopback for the cluster tests and the benchmark: a head and worker nodes
(``ray.cluster_utils.Cluster``), every port Ray would otherwise take at a fixed default chosen free at run
time, its files in a folder of its own (``RAY_TMPDIR``: no ``ray_current_cluster`` shared with other
sessions), stopped by whoever started it (``stop``: the nodes' own processes).

    with LoopbackCluster(head_cpus=0, nodes=(1, 1)) as c:   # c.address: HOST:PORT; c.env: a driver's env
        subprocess.run(["homeo-sim", "run", "--seeds", "4", "--cluster", c.address], env=c.env)
"""

from __future__ import annotations

import os
import shutil
import socket
import tempfile

ENV = {"RAY_ENABLE_WINDOWS_OR_OSX_CLUSTER": "0", "RAY_USAGE_STATS_ENABLED": "0"}


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class LoopbackCluster:
    def __init__(self, head_cpus: int = 1, nodes: tuple = (1,)):
        self.head_cpus, self.node_cpus = head_cpus, nodes
        self.cluster = None
        self.nodes: list = []

    @staticmethod
    def _ports() -> dict:
        # ports Ray otherwise takes at a fixed default (two test workers would share them); the rest are 0: the kernel's
        return {"dashboard_agent_listen_port": free_port(), "metrics_export_port": free_port(),
                "runtime_env_agent_port": free_port()}

    def start(self) -> "LoopbackCluster":
        self.tmp = tempfile.mkdtemp(prefix="ray", dir="/tmp")  # short: Ray's socket paths are limited to 107 bytes
        self.env = {**os.environ, **ENV, "RAY_TMPDIR": self.tmp}
        os.environ.update({**ENV, "RAY_TMPDIR": self.tmp})  # Cluster starts the nodes with this process's env
        try:
            return self._start()
        except BaseException:
            self.stop()  # a node that did not come up (a busy machine): what did is stopped, the folder removed
            raise

    def _start(self) -> "LoopbackCluster":
        from ray.cluster_utils import Cluster

        self.cluster = Cluster(initialize_head=True, shutdown_at_exit=True, head_node_args=dict(
            node_ip_address="127.0.0.1", num_cpus=self.head_cpus, include_dashboard=False,
            gcs_server_port=free_port(), **self._ports()))
        self.nodes = [self.cluster.add_node(node_ip_address="127.0.0.1", num_cpus=n, **self._ports())
                      for n in self.node_cpus]
        self.cluster.wait_for_nodes()
        self.address = self.cluster.address
        return self

    def kill(self, node) -> None:
        """Stop a worker node's processes at once (a machine lost mid-study)."""
        self.cluster.remove_node(node, allow_graceful=False)
        self.nodes.remove(node)

    def stop(self) -> None:
        if self.cluster is not None:
            import ray

            ray.shutdown()  # this process's own driver, if it was one (the cluster stops only without one)
            self.cluster.shutdown()
            self.cluster = None
        self.nodes = []
        shutil.rmtree(self.tmp, ignore_errors=True)
        os.environ.pop("RAY_TMPDIR", None)

    def __enter__(self):
        return self.start()

    def __exit__(self, *exc):
        self.stop()
