#!/usr/bin/env python3
"""Writes an ONNX model with the compute of a small YOLOv8-seg at 640x640 for bench/detector_share
(no trained weights: Debian's python3-onnx + python3-numpy only).

The network runs a conv stack shaped like YOLOv8n-seg's (3x3 convs, widths 16-256 over strides
2-32, a neck back up to stride 8 and the prototype branch at stride 4) on the real image, then
emits the YOLOv8-seg layout: output0 [1, 4 + 80 + 32, 8400] and output1 [1, 32, 160, 160]. The
prototypes are computed from the stride-4 features; output0 is a constant (a zero-weight 1x1
conv of the pooled features plus a bias) whose class scores all lie below the plugin's score
threshold, so the plugin does its whole decode and returns no detection: the bench measures
the detector's share of the cores, and the SLAM gets its detections from the scene.

Usage: make_detector_model.py <out.onnx>   (prints the model's multiply-adds)
"""
import os
import sys

import numpy as np
import onnx
from onnx import TensorProto, helper, numpy_helper

INPUT = 640
NC, NM, ANCHORS = 80, 32, 8400


def main(path):
    rng = np.random.default_rng(1)
    nodes, inits = [], []
    macs = 0

    def conv(x, cin, cout, size, stride, hw_out, name):
        nonlocal macs
        w = rng.normal(0, np.sqrt(2.0 / (cin * size * size)), (cout, cin, size, size))
        inits.append(numpy_helper.from_array(w.astype(np.float32), name + "_w"))
        inits.append(numpy_helper.from_array(np.zeros(cout, np.float32), name + "_b"))
        pad = size // 2
        nodes.append(helper.make_node("Conv", [x, name + "_w", name + "_b"], [name + "_c"],
                                      kernel_shape=[size, size], strides=[stride, stride],
                                      pads=[pad, pad, pad, pad]))
        nodes.append(helper.make_node("Relu", [name + "_c"], [name]))
        macs += cin * cout * size * size * hw_out * hw_out
        return name

    # Backbone: stride 2, 4, 8, 16, 32 with two 3x3 convs after each stride-2 conv (from 4 on).
    x = conv("images", 3, 16, 3, 2, 320, "b0")
    widths = [(16, 32, 160), (32, 64, 80), (64, 128, 40), (128, 256, 20)]
    taps = {}
    for i, (cin, cout, hw) in enumerate(widths):
        x = conv(x, cin, cout, 3, 2, hw, "b%d_down" % (i + 1))
        for k in range(2):
            x = conv(x, cout, cout, 3, 1, hw, "b%d_%d" % (i + 1, k))
        taps[hw] = (x, cout)
    # Neck: upsample to stride 16 and 8, a 3x3 conv each; back down to stride 16 and 32.
    up = x
    for hw, cin in ((40, 256), (80, 128)):
        nodes.append(helper.make_node("Resize", [up, "roi", "scale2"], [up + "_up"], mode="nearest"))
        tap, cout = taps[hw]
        nodes.append(helper.make_node("Concat", [up + "_up", tap], [up + "_cat"], axis=1))
        up = conv(up + "_cat", cin + cout, cout, 3, 1, hw, "n%d" % hw)
    inits.append(numpy_helper.from_array(np.array([1, 1, 2, 2], np.float32), "scale2"))
    inits.append(numpy_helper.from_array(np.zeros(0, np.float32), "roi"))
    n80 = up
    d40 = conv(n80, 64, 64, 3, 2, 40, "n_down40")
    d40 = conv(d40, 64, 128, 3, 1, 40, "n40b")
    d20 = conv(d40, 128, 128, 3, 2, 20, "n_down20")
    d20 = conv(d20, 128, 256, 3, 1, 20, "n20b")
    # Heads: per scale two 3x3 convs (box and class branches in YOLOv8, here one of each).
    for name, src, c, hw in (("h80", n80, 64, 80), ("h40", d40, 128, 40), ("h20", d20, 256, 20)):
        h = conv(src, c, 64, 3, 1, hw, name + "_box")
        conv(h, 64, 64, 3, 1, hw, name + "_box2")
        h = conv(src, c, 80, 3, 1, hw, name + "_cls")
        conv(h, 80, 80, 3, 1, hw, name + "_cls2")
    # Prototypes at stride 4 (160x160) from the stride-8 features, upsampled.
    nodes.append(helper.make_node("Resize", [n80, "roi", "scale2"], ["p_up"], mode="nearest"))
    p = conv("p_up", 64, 64, 3, 1, 160, "p0")
    nodes.append(helper.make_node("Conv", [p, "proto_w", "proto_b"], ["output1"],
                                  kernel_shape=[1, 1]))
    inits.append(numpy_helper.from_array(
        rng.normal(0, 0.1, (NM, 64, 1, 1)).astype(np.float32), "proto_w"))
    inits.append(numpy_helper.from_array(np.zeros(NM, np.float32), "proto_b"))
    macs += 64 * NM * 160 * 160

    # output0: a constant. Candidate boxes spread over the input, class scores below 0.25.
    pred = np.zeros((4 + NC + NM, ANCHORS), np.float32)
    pred[0] = rng.uniform(0, INPUT, ANCHORS)
    pred[1] = rng.uniform(0, INPUT, ANCHORS)
    pred[2:4] = rng.uniform(10, 200, (2, ANCHORS))
    pred[4:4 + NC] = rng.uniform(0.0, 0.2, (NC, ANCHORS))
    pred[4 + NC:] = rng.uniform(-1, 1, (NM, ANCHORS))
    nodes.append(helper.make_node("GlobalAveragePool", [x], ["pooled"]))
    nodes.append(helper.make_node("Conv", ["pooled", "z_w"], ["zero"], kernel_shape=[1, 1]))
    nodes.append(helper.make_node("Conv", ["zero", "o_w", "o_b"], ["o_c"], kernel_shape=[1, 1]))
    nodes.append(helper.make_node("Reshape", ["o_c", "o_shape"], ["output0"]))
    inits += [
        numpy_helper.from_array(np.zeros((1, 256, 1, 1), np.float32), "z_w"),
        numpy_helper.from_array(np.zeros((pred.size, 1, 1, 1), np.float32), "o_w"),
        numpy_helper.from_array(pred.reshape(-1), "o_b"),
        numpy_helper.from_array(np.array([1, 4 + NC + NM, ANCHORS], np.int64), "o_shape"),
    ]
    graph = helper.make_graph(
        nodes, "emf_detector_share",
        [helper.make_tensor_value_info("images", TensorProto.FLOAT, [1, 3, INPUT, INPUT])],
        [helper.make_tensor_value_info("output0", TensorProto.FLOAT, [1, 4 + NC + NM, ANCHORS]),
         helper.make_tensor_value_info("output1", TensorProto.FLOAT, [1, NM, 160, 160])],
        initializer=inits)
    model = helper.make_model(graph, opset_imports=[helper.make_opsetid("", 12)])
    model.ir_version = 7
    onnx.checker.check_model(model)
    tmp = path + ".tmp"
    onnx.save(model, tmp)
    os.replace(tmp, path)
    print("%s: %.2f G multiply-adds per frame" % (path, macs / 1e9))


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    main(sys.argv[1])
