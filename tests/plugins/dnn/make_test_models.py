#!/usr/bin/env python3
"""Builds the small ONNX models the dnn plugin tests run (no trained weights needed).

Each model ignores its image (GlobalAveragePool -> 1x1 Conv with zero weights) and emits
constant tensors through 1x1 Convs whose biases hold the values, reshaped to the layout's
shapes; OpenCV 4.6's importer handles these ops (it cannot broadcast an Add of a constant).
A Reshape of the input to its own fixed shape makes the model reject other input sizes, like
a real static export.

The tensors encode objects defined in colour-image ("frame") pixels; every model comes with a
JSON file holding that ground truth, which the tests compare the plugin's output against:
  objects: class_id, score, box [x1, y1, x2, y2) and the mask as rectangles [x1, y1, x2, y2):
  mask = (union of `add`) minus (union of `sub`), cropped to the box.
Rectangle edges lie on the prototype / mask-cell grid, so the expected masks are exact.

Usage: make_test_models.py <output folder>
"""
import json
import os
import sys

import numpy as np
import onnx
from onnx import TensorProto, helper, numpy_helper

FRAME_W, FRAME_H = 640, 480
LOGIT = 8.0  # |logit| of mask pixels inside / outside a shape


def letterbox(input_w, input_h):
    """(scale, pad_x, pad_y) of the frame letterboxed into the input (aspect kept, centred)."""
    r = min(input_w / FRAME_W, input_h / FRAME_H)
    new_w, new_h = round(FRAME_W * r), round(FRAME_H * r)
    return new_w / FRAME_W, (input_w - new_w) // 2, (input_h - new_h) // 2


def inside(rects, x, y):
    """Boolean array: points (x, y) (frame pixels) inside any of `rects`."""
    hit = np.zeros(np.broadcast(x, y).shape, bool)
    for x1, y1, x2, y2 in rects:
        hit |= (x >= x1) & (x < x2) & (y >= y1) & (y < y2)
    return hit


def shape_at(obj, x, y):
    return inside(obj["add"], x, y) & ~inside(obj.get("sub", []), x, y)


def save_model(path, input_w, input_h, outputs, head_nodes=(), head_inits=(), graph_outputs=None):
    """A model taking images [1, 3, input_h, input_w] and emitting the constant `outputs`
    (list of (name, array)); `head_nodes` may compute the graph outputs (`graph_outputs`:
    list of (name, shape)) from those constants instead."""
    nodes = [
        helper.make_node("Reshape", ["images", "input_shape"], ["fixed"]),
        helper.make_node("GlobalAveragePool", ["fixed"], ["pooled"]),
        helper.make_node("Conv", ["pooled", "w_zero"], ["zero"], kernel_shape=[1, 1]),
    ]
    inits = [
        numpy_helper.from_array(np.array([1, 3, input_h, input_w], np.int64), "input_shape"),
        numpy_helper.from_array(np.zeros((1, 3, 1, 1), np.float32), "w_zero"),
    ]
    infos = []
    for name, value in outputs:
        value = np.ascontiguousarray(value, np.float32)
        nodes.append(helper.make_node("Conv", ["zero", "w_" + name, "b_" + name], ["c_" + name],
                                      kernel_shape=[1, 1]))
        nodes.append(helper.make_node("Reshape", ["c_" + name, "s_" + name], [name]))
        inits += [
            numpy_helper.from_array(np.zeros((value.size, 1, 1, 1), np.float32), "w_" + name),
            numpy_helper.from_array(value.reshape(-1), "b_" + name),
            numpy_helper.from_array(np.array(value.shape, np.int64), "s_" + name),
        ]
        infos.append(helper.make_tensor_value_info(name, TensorProto.FLOAT, list(value.shape)))
    nodes += list(head_nodes)
    inits += list(head_inits)
    if graph_outputs is not None:
        infos = [helper.make_tensor_value_info(n, TensorProto.FLOAT, list(shape))
                 for n, shape in graph_outputs]
    graph = helper.make_graph(
        nodes, "emf_dnn_test",
        [helper.make_tensor_value_info("images", TensorProto.FLOAT, [1, 3, input_h, input_w])],
        infos, initializer=inits)
    model = helper.make_model(graph, opset_imports=[helper.make_opsetid("", 12)])
    model.ir_version = 7
    onnx.checker.check_model(model)
    tmp = path + ".tmp"
    onnx.save(model, tmp)
    os.replace(tmp, path)


def save_truth(path, input_w, input_h, objects, extra=None):
    truth = {"frame": [FRAME_W, FRAME_H], "input": [input_w, input_h], "objects": objects}
    truth.update(extra or {})
    tmp = path + ".tmp"
    with open(tmp, "w") as f:
        json.dump(truth, f, indent=1)
    os.replace(tmp, path)


# Two objects in frame pixels. A: an L-ish "person" (head + body); B: a "cup" whose prototype
# shape (with a hole) is larger than its box, so the crop to the box shows. B's box edges are
# off the 4-px prototype grid but even, so they stay exact in a half-size depth image.
PERSON = {"class_id": 0, "class_name": "person", "score": 0.91, "box": [100, 60, 260, 360],
          "add": [[148, 60, 212, 120], [100, 120, 260, 360]]}
CUP = {"class_id": 41, "class_name": "cup", "score": 0.78, "box": [402, 202, 546, 330],
       "add": [[380, 200, 560, 340]], "sub": [[440, 240, 480, 280]]}


def yolo_model(out_dir, rng):
    input_w, input_h, nc, nm, n = 640, 640, 80, 32, 64
    mh, mw = input_h // 4, input_w // 4
    s, px, py = letterbox(input_w, input_h)
    # Prototype pixel centres in frame pixels.
    gx = ((np.arange(mw) + 0.5) * (input_w / mw) - px) / s
    gy = ((np.arange(mh) + 0.5) * (input_h / mh) - py) / s
    X, Y = np.meshgrid(gx, gy)
    protos = rng.uniform(-1, 1, (1, nm, mh, mw)).astype(np.float32)
    protos[0, 0] = np.where(shape_at(PERSON, X, Y), LOGIT, -LOGIT)
    protos[0, 1] = np.where(shape_at(CUP, X, Y), LOGIT, -LOGIT)
    protos[0, 2] = 1.0

    pred = np.zeros((1, 4 + nc + nm, n), np.float32)
    # Background candidates: random boxes, low scores, random coefficients.
    pred[0, 0] = rng.uniform(0, input_w, n)
    pred[0, 1] = rng.uniform(0, input_h, n)
    pred[0, 2] = rng.uniform(10, 100, n)
    pred[0, 3] = rng.uniform(10, 100, n)
    pred[0, 4:4 + nc] = rng.uniform(0.0, 0.05, (nc, n))
    pred[0, 4 + nc:] = rng.uniform(-1, 1, (nm, n))

    def put(anchor, obj, score, coeffs, shift=0.0):
        x1, y1, x2, y2 = obj["box"]
        pred[0, 0, anchor] = ((x1 + x2) / 2 + shift) * s + px
        pred[0, 1, anchor] = ((y1 + y2) / 2 + shift) * s + py
        pred[0, 2, anchor] = (x2 - x1) * s
        pred[0, 3, anchor] = (y2 - y1) * s
        pred[0, 4:4 + nc, anchor] = 0.001
        pred[0, 4 + obj["class_id"], anchor] = score
        c = rng.uniform(-0.02, 0.02, nm)  # sums to |logit| < 0.6 over the noise prototypes
        c[:3] = coeffs
        pred[0, 4 + nc:, anchor] = c

    put(17, PERSON, PERSON["score"], [1.0, 0.0, 0.5])
    put(40, CUP, CUP["score"], [0.0, 1.0, -0.5])
    put(5, PERSON, 0.6, [1.0, 0.0, 0.0], shift=6.0)  # duplicate: removed by NMS
    chair = {"class_id": 56, "box": [300, 100, 380, 200]}
    put(50, chair, 0.2, [0.0, 0.0, 1.0])  # below the 0.25 score threshold

    path = os.path.join(out_dir, "yolov8_seg.onnx")
    save_model(path, input_w, input_h, [("output0", pred), ("output1", protos)])
    save_truth(os.path.join(out_dir, "yolov8_seg.json"), input_w, input_h, [PERSON, CUP])
    # Detection-only export (no prototypes): shapes match neither layout.
    save_model(os.path.join(out_dir, "yolov8_detect.onnx"), input_w, input_h,
               [("output0", pred[:, :4 + nc, :])])


def maskrcnn_model(out_dir, rng):
    # 800x800 input: the frame is scaled by 1.25 and padded 100 px top and bottom.
    input_w, input_h, cells = 800, 800, 28
    s, px, py = letterbox(input_w, input_h)
    # Boxes are whole multiples of the 28-cell grid in frame pixels (6 and 10 px per cell).
    person = {"class_id": 0, "class_name": "person", "score": 0.95, "box": [60, 40, 228, 320],
              "add": [[96, 40, 192, 100], [60, 100, 228, 320]]}
    cup = {"class_id": 41, "class_name": "cup", "score": 0.85, "box": [400, 200, 512, 312],
           "add": [[400, 200, 512, 312]], "sub": [[432, 232, 480, 280]]}
    dup = dict(cup, score=0.5, box=[404, 204, 516, 316])  # duplicate: removed by NMS
    low = {"class_id": 56, "score": 0.1, "box": [300, 50, 400, 150], "add": [[300, 50, 400, 150]]}
    objs = [low, person, dup, cup]
    boxes = np.zeros((len(objs), 4), np.float32)
    masks = np.zeros((len(objs), 1, cells, cells), np.float32)
    for i, o in enumerate(objs):
        x1, y1, x2, y2 = o["box"]
        boxes[i] = [x1 * s + px, y1 * s + py, x2 * s + px, y2 * s + py]
        cx = x1 + (np.arange(cells) + 0.5) * (x2 - x1) / cells
        cy = y1 + (np.arange(cells) + 0.5) * (y2 - y1) / cells
        X, Y = np.meshgrid(cx, cy)
        masks[i, 0] = np.where(shape_at(o, X, Y), LOGIT, -LOGIT)
        masks[i, 0] += rng.uniform(-0.5, 0.5, (cells, cells))
    labels = np.array([o["class_id"] for o in objs], np.float32)
    scores = np.array([o["score"] for o in objs], np.float32)
    outputs = [("boxes", boxes), ("labels", labels), ("scores", scores)]
    save_model(os.path.join(out_dir, "maskrcnn.onnx"), input_w, input_h,
               outputs + [("masks", masks)])
    save_model(os.path.join(out_dir, "maskrcnn_prob.onnx"), input_w, input_h,
               outputs + [("masks", 1.0 / (1.0 + np.exp(-masks)))])
    truth_objs = [person, cup]
    save_truth(os.path.join(out_dir, "maskrcnn.json"), input_w, input_h, truth_objs)


def yolo_head_model(out_dir, rng):
    """A YOLOv8-seg export's head in miniature, with the ops a real export has: Split of the
    head features, the DFL (Reshape, Transpose, Softmax, Conv), box decoding against the anchor
    grid (Sub, Add, Div, Concat), the strides Mul with a [1, N] constant that OpenCV 4.6 cannot
    broadcast (scripts/onnx_for_opencv.py converts it), Sigmoid of the class logits, Concat.
    The head features are constants encoding two objects. Input 320x320 (frame scale 0.5,
    pad_y 40), stride 8 (40x40 anchors), prototypes 80x80."""
    input_w = input_h = 320
    stride, grid, reg, nc, nm = 8, 40, 16, 80, 32
    n = grid * grid
    mh = mw = input_h // 4
    s, px, py = letterbox(input_w, input_h)
    feat = np.zeros((1, 4 * reg + nc + nm, n), np.float32)
    feat[0, 4 * reg:4 * reg + nc] = -6.0  # class logits: sigmoid 0.0025, below any threshold
    feat[0, 4 * reg + nc:] = rng.uniform(-1, 1, (nm, n))

    gx = ((np.arange(mw) + 0.5) * (input_w / mw) - px) / s
    gy = ((np.arange(mh) + 0.5) * (input_h / mh) - py) / s
    X, Y = np.meshgrid(gx, gy)
    # Frame boxes from anchor cell (i, j) and DFL distances (l, t, r, b) in grid cells.
    person = {"class_id": 0, "class_name": "person", "score": 0.91, "cell": (12, 17),
              "dist": (6, 9, 8, 7), "add": [[184, 56, 248, 120], [104, 120, 328, 312]]}
    cup = {"class_id": 41, "class_name": "cup", "score": 0.78, "cell": (30, 25),
           "dist": (3, 2, 4, 5), "add": [[424, 288, 560, 416]], "sub": [[472, 328, 512, 368]]}
    protos = rng.uniform(-1, 1, (1, nm, mh, mw)).astype(np.float32)
    protos[0, 2] = 1.0
    for k, (obj, coeffs) in enumerate([(person, [1.0, 0.0, 0.5]), (cup, [0.0, 1.0, -0.5])]):
        i, j = obj["cell"]
        l, t, r, b = obj["dist"]
        ax, ay = (i + 0.5) * stride, (j + 0.5) * stride  # input pixels
        x1, y1, x2, y2 = ax - l * stride, ay - t * stride, ax + r * stride, ay + b * stride
        obj["box"] = [(x1 - px) / s, (y1 - py) / s, (x2 - px) / s, (y2 - py) / s]
        a = j * grid + i
        for side, d in enumerate((l, t, r, b)):
            feat[0, side * reg:(side + 1) * reg, a] = 0.0
            feat[0, side * reg + d, a] = 30.0  # softmax ~ one-hot: distance d
        feat[0, 4 * reg + obj["class_id"], a] = np.log(obj["score"] / (1 - obj["score"]))
        c = rng.uniform(-0.02, 0.02, nm)
        c[:3] = coeffs
        feat[0, 4 * reg + nc:, a] = c
        protos[0, k] = np.where(shape_at(obj, X, Y), LOGIT, -LOGIT)
        del obj["cell"], obj["dist"]

    ax, ay = np.meshgrid(np.arange(grid) + 0.5, np.arange(grid) + 0.5)
    anchors = np.stack([ax.ravel(), ay.ravel()])[None].astype(np.float32)  # [1, 2, n]
    node = helper.make_node
    head = [
        node("Split", ["feat"], ["box", "cls", "mc"], axis=1, split=[4 * reg, nc, nm]),
        node("Reshape", ["box", "dfl_shape"], ["box4"]),
        node("Transpose", ["box4"], ["box_t"], perm=[0, 2, 1, 3]),
        node("Softmax", ["box_t"], ["box_p"], axis=1),
        node("Conv", ["box_p", "dfl_w"], ["dist_c"], kernel_shape=[1, 1]),
        node("Reshape", ["dist_c", "dist_shape"], ["dist"]),
        node("Split", ["dist"], ["lt", "rb"], axis=1, split=[2, 2]),
        node("Sub", ["anchors", "lt"], ["x1y1"]),
        node("Add", ["anchors", "rb"], ["x2y2"]),
        node("Add", ["x1y1", "x2y2"], ["sum_xy"]),
        node("Div", ["sum_xy", "two"], ["cxy"]),
        node("Sub", ["x2y2", "x1y1"], ["wh"]),
        node("Concat", ["cxy", "wh"], ["dbox_cells"], axis=1),
        node("Mul", ["dbox_cells", "strides"], ["dbox"]),
        node("Sigmoid", ["cls"], ["scores"]),
        node("Concat", ["dbox", "scores", "mc"], ["output0"], axis=1),
        node("Identity", ["protos"], ["output1"]),
    ]
    inits = [
        numpy_helper.from_array(np.array([1, 4, reg, n], np.int64), "dfl_shape"),
        numpy_helper.from_array(np.arange(reg, dtype=np.float32).reshape(1, reg, 1, 1), "dfl_w"),
        numpy_helper.from_array(np.array([1, 4, n], np.int64), "dist_shape"),
        numpy_helper.from_array(anchors, "anchors"),
        numpy_helper.from_array(np.array([2.0], np.float32), "two"),
        numpy_helper.from_array(np.full((1, n), float(stride), np.float32), "strides"),
    ]
    save_model(os.path.join(out_dir, "yolov8_head.onnx"), input_w, input_h,
               [("feat", feat), ("protos", protos)], head, inits,
               [("output0", (1, 4 + nc + nm, n)), ("output1", (1, nm, mh, mw))])
    save_truth(os.path.join(out_dir, "yolov8_head.json"), input_w, input_h, [person, cup])


def main():
    if len(sys.argv) != 2:
        sys.exit("usage: make_test_models.py <output folder>")
    out_dir = sys.argv[1]
    os.makedirs(out_dir, exist_ok=True)
    rng = np.random.default_rng(8)
    yolo_model(out_dir, rng)
    maskrcnn_model(out_dir, rng)
    yolo_head_model(out_dir, rng)


if __name__ == "__main__":
    main()
