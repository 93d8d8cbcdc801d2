#!/usr/bin/env python3
"""Example ROS 2 node: segment every map on ``/map`` and publish its rooms for RViz.

An example, not part of the topomap package. Running it needs a ROS 2
installation (``rclpy``, ``nav_msgs``, ``sensor_msgs``,
``visualization_msgs``; source its ``setup.bash``) and
``pip install 'topomap-rooms[ros]'`` in the same Python::

    python3 examples/ros2_node.py

It subscribes to ``/map`` (``nav_msgs/OccupancyGrid``, transient local, as
``map_server`` and SLAM nodes publish it), segments each map it receives and
publishes, transient local so that an RViz started later still gets them:

* ``/topomap/rooms`` -- ``visualization_msgs/MarkerArray``: room outlines,
  room numbers, door segments, in the map's frame;
* ``/topomap/labels`` -- ``sensor_msgs/Image`` (``mono16``): the room label
  of every map cell.

The message building, :func:`segment_map_message`, needs no ROS: it takes
any object with the fields of an OccupancyGrid (an ``rclpy`` message here)
and returns the serialized messages; the node only deserializes them into
its own ``rclpy`` types and publishes them.
"""

import topomap
from topomap import ros


def segment_map_message(msg, *, method=None):
    """Segment one ``nav_msgs/OccupancyGrid`` message.

    Parameters
    ----------
    msg : nav_msgs/OccupancyGrid
        An ``rclpy`` message (or a ``rosbags`` one, or any object with its
        fields).
    method : str, optional
        Segmentation method (default topomap's).

    Returns
    -------
    seg : topomap.segmentation.Segmentation
    markers : bytes
        CDR of the ``visualization_msgs/MarkerArray`` (:func:`topomap.ros.marker_array`).
    labels : bytes
        CDR of the ``sensor_msgs/Image`` (:func:`topomap.ros.label_image`).
    """
    grid = ros.grid_from_message(msg, source="/map")
    seg = topomap.segment(grid) if method is None else topomap.segment(grid, method=method)
    return seg, ros.to_cdr(ros.marker_array(seg)), ros.to_cdr(ros.label_image(seg))


def main(args=None):
    import rclpy
    from nav_msgs.msg import OccupancyGrid
    from rclpy.node import Node
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
    from rclpy.serialization import deserialize_message
    from sensor_msgs.msg import Image
    from visualization_msgs.msg import MarkerArray

    latched = QoSProfile(depth=1, durability=DurabilityPolicy.TRANSIENT_LOCAL,
                         reliability=ReliabilityPolicy.RELIABLE)

    class RoomsNode(Node):
        def __init__(self):
            super().__init__("topomap_rooms")
            self.markers = self.create_publisher(MarkerArray, ros.MARKERS_TOPIC, latched)
            self.labels = self.create_publisher(Image, ros.LABELS_TOPIC, latched)
            self.create_subscription(OccupancyGrid, "map", self.on_map, latched)

        def on_map(self, msg):
            try:
                seg, markers, labels = segment_map_message(msg)
            except topomap.TopomapError as exc:  # a map topomap cannot use: say why, keep running
                self.get_logger().error(str(exc))
                return
            self.markers.publish(deserialize_message(markers, MarkerArray))
            self.labels.publish(deserialize_message(labels, Image))
            self.get_logger().info(f"{seg.n_rooms} rooms, {len(seg.doors)} doors")

    rclpy.init(args=args)
    node = RoomsNode()
    try:
        rclpy.spin(node)
    except KeyboardInterrupt:
        pass
    finally:
        node.destroy_node()
        rclpy.try_shutdown()


if __name__ == "__main__":
    main()
