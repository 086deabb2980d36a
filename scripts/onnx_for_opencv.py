#!/usr/bin/env python3
"""Rewrites an ONNX model so that OpenCV 4.6 (Debian 12) can run it with the emf `dnn` plugin.

OpenCV 4.6's DNN cannot broadcast a constant operand of an elementwise Add/Sub/Mul/Div to the
other operand's shape (YOLOv8/YOLO11 exports multiply the decoded boxes [1, 4, N] by a strides
constant [1, N]; the first forward pass then fails with "shape_utils.hpp ... total"), nor take
an elementwise op whose operands are both constants of different shapes ("parseBias
blob_0.size == blob_1.size"). This tool, with only python3-onnx and python3-numpy:
  - folds elementwise ops whose operands are all constants into one constant;
  - replaces a constant operand (more than one element) whose shape differs from the op's
    output shape by the constant broadcast to that shape.
The model's numbers do not change. It needs static shapes (export with a fixed imgsz).

Usage: onnx_for_opencv.py in.onnx out.onnx
"""
import os
import sys

import numpy as np
import onnx
from onnx import numpy_helper, shape_inference

ELEMENTWISE = {"Add": np.add, "Sub": np.subtract, "Mul": np.multiply, "Div": np.divide}


def static_shapes(model):
    """Output name -> static shape (tuple) for every tensor shape inference can size."""
    inferred = shape_inference.infer_shapes(model)
    shapes = {}
    for vi in list(inferred.graph.value_info) + list(inferred.graph.output) + list(
            inferred.graph.input):
        dims = vi.type.tensor_type.shape.dim
        if dims and all(d.HasField("dim_value") for d in dims):
            shapes[vi.name] = tuple(d.dim_value for d in dims)
    return shapes


def constants(graph):
    """Name -> numpy array for initializers and Constant nodes (with a `value` tensor)."""
    out = {init.name: numpy_helper.to_array(init) for init in graph.initializer}
    for node in graph.node:
        if node.op_type == "Constant":
            for attr in node.attribute:
                if attr.name == "value":
                    out[node.output[0]] = numpy_helper.to_array(attr.t)
    return out


def rewrite(model):
    graph = model.graph
    shapes = static_shapes(model)
    consts = constants(graph)
    folded = expanded = 0
    new_nodes = []
    new_inits = []
    for node in graph.node:
        if node.op_type not in ELEMENTWISE or len(node.input) != 2:
            new_nodes.append(node)
            continue
        a, b = node.input
        if a in consts and b in consts:
            value = ELEMENTWISE[node.op_type](consts[a], consts[b]).astype(consts[a].dtype)
            consts[node.output[0]] = value
            new_inits.append(numpy_helper.from_array(value, node.output[0]))
            folded += 1
            continue
        out_shape = shapes.get(node.output[0])
        inputs = list(node.input)
        for i, name in enumerate(inputs):
            c = consts.get(name)
            if c is None or c.size <= 1 or out_shape is None or tuple(c.shape) == out_shape:
                continue
            full = np.ascontiguousarray(np.broadcast_to(c, out_shape))
            full_name = f"{name}__broadcast_{'x'.join(map(str, out_shape))}"
            if full_name not in consts:
                consts[full_name] = full
                new_inits.append(numpy_helper.from_array(full, full_name))
            inputs[i] = full_name
            expanded += 1
        del node.input[:]
        node.input.extend(inputs)
        new_nodes.append(node)
    del graph.node[:]
    graph.node.extend(new_nodes)
    graph.initializer.extend(new_inits)
    return folded, expanded


def main():
    if len(sys.argv) != 3:
        sys.exit("usage: onnx_for_opencv.py in.onnx out.onnx")
    model = onnx.load(sys.argv[1])
    folded, expanded = rewrite(model)
    onnx.checker.check_model(model)
    tmp = sys.argv[2] + ".tmp"
    onnx.save(model, tmp)
    os.replace(tmp, sys.argv[2])
    print(f"onnx_for_opencv: {sys.argv[2]}: folded {folded} constant op(s), broadcast "
          f"{expanded} constant operand(s)")


if __name__ == "__main__":
    main()
