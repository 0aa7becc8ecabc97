#!/usr/bin/env python3
"""Writes a tiny ONNX semantic segmentation network that labels pixels by colour.

Used by the tests (built at test time, no downloaded weights) and handy for trying the
ImageLabelTransfer nodelet and urban_detection_spark without a real model.

  spark_colour_model.py OUT.onnx WIDTH HEIGHT [NAMES.txt]

Input  "image":  float [1, 3, HEIGHT, WIDTH], RGB scaled to [0, 1] (mean 0, scale 1/255).
Output "scores": float [1, 4, HEIGHT, WIDTH], logits of the classes
  0 background (grey, black, white), 1 car (red), 2 vegetation (green), 3 pole (blue).
A 1x1 convolution computes 2*own - other two channels per colour class and a constant 0.5 for
the background, then Relu and a multiplication by 4 sharpen the softmax. Only Conv, Relu and
Mul at opset 11, which OpenCV 4.6's ONNX importer accepts.
"""
import sys

import numpy as np
import onnx
from onnx import TensorProto, helper, numpy_helper

CLASS_NAMES = ["background", "car", "vegetation", "pole"]


def build(width, height):
    weights = np.array([[0, 0, 0], [2, -1, -1], [-1, 2, -1], [-1, -1, 2]],
                       dtype=np.float32).reshape(4, 3, 1, 1)
    bias = np.array([0.5, 0, 0, 0], dtype=np.float32)
    gain = np.array([4.0], dtype=np.float32)
    nodes = [
        helper.make_node("Conv", ["image", "w", "b"], ["logits"], kernel_shape=[1, 1]),
        helper.make_node("Relu", ["logits"], ["positive"]),
        helper.make_node("Mul", ["positive", "gain"], ["scores"]),
    ]
    graph = helper.make_graph(
        nodes, "colour_segmentation",
        [helper.make_tensor_value_info("image", TensorProto.FLOAT, [1, 3, height, width])],
        [helper.make_tensor_value_info("scores", TensorProto.FLOAT, [1, 4, height, width])],
        initializer=[numpy_helper.from_array(weights, "w"), numpy_helper.from_array(bias, "b"),
                     numpy_helper.from_array(gain, "gain")])
    model = helper.make_model(graph, opset_imports=[helper.make_opsetid("", 11)],
                              producer_name="urban_detection tests")
    model.ir_version = 7
    onnx.checker.check_model(model)
    return model


def main():
    if len(sys.argv) not in (4, 5):
        sys.stderr.write(__doc__)
        return 2
    onnx.save(build(int(sys.argv[2]), int(sys.argv[3])), sys.argv[1])
    if len(sys.argv) == 5:
        with open(sys.argv[4], "w") as f:
            f.write("\n".join(CLASS_NAMES) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
