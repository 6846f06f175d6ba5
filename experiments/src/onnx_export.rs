//! Writing small feed-forward networks as ONNX files: the graph is assembled from the ONNX
//! protobuf messages that `tract-onnx` ships (`tract_onnx::pb`, the ONNX IR's `onnx.proto`)
//! and encoded with `prost`. Operators: `Conv`, `Relu`, `Tanh`, `Flatten`, `Gemm`, `Concat`,
//! `Mul`, `Add`, `Div`, `Expand`, `ReduceSum`, `Identity` (opset 13, the semantics of the ONNX operator documentation).

use prost::Message;
use tract_onnx::pb;

/// ONNX IR version written (ONNX 1.10+).
const IR_VERSION: i64 = 8;
/// Default-domain opset written.
const OPSET: i64 = 13;
/// `TensorProto.DataType.FLOAT`.
const FLOAT: i32 = 1;

/// `TensorProto.DataType.INT64`.
const INT64: i32 = 7;

/// A graph under construction: nodes in topological order, weights as initializers.
#[derive(Debug, Default)]
pub struct Graph {
    nodes: Vec<pb::NodeProto>,
    initializers: Vec<pb::TensorProto>,
    inputs: Vec<pb::ValueInfoProto>,
    outputs: Vec<pb::ValueInfoProto>,
    next: usize,
}

fn value_info(name: &str, shape: &[usize]) -> pb::ValueInfoProto {
    use pb::tensor_shape_proto::{dimension::Value as Dim, Dimension};
    pb::ValueInfoProto {
        name: name.to_owned(),
        r#type: Some(pb::TypeProto {
            value: Some(pb::type_proto::Value::TensorType(pb::type_proto::Tensor {
                elem_type: FLOAT,
                shape: Some(pb::TensorShapeProto {
                    dim: shape
                        .iter()
                        .map(|&d| Dimension {
                            value: Some(Dim::DimValue(d as i64)),
                            ..Default::default()
                        })
                        .collect(),
                }),
            })),
            ..Default::default()
        }),
        ..Default::default()
    }
}

fn ints(name: &str, values: &[i64]) -> pb::AttributeProto {
    pb::AttributeProto {
        name: name.to_owned(),
        r#type: pb::attribute_proto::AttributeType::Ints as i32,
        ints: values.to_vec(),
        ..Default::default()
    }
}

fn int(name: &str, value: i64) -> pb::AttributeProto {
    pb::AttributeProto {
        name: name.to_owned(),
        r#type: pb::attribute_proto::AttributeType::Int as i32,
        i: value,
        ..Default::default()
    }
}

impl Graph {
    /// An empty graph.
    pub fn new() -> Self {
        Self::default()
    }

    fn fresh(&mut self, op: &str) -> String {
        self.next += 1;
        format!("{}_{}", op.to_lowercase(), self.next)
    }

    fn node(&mut self, op: &str, inputs: &[&str], attributes: Vec<pb::AttributeProto>) -> String {
        let out = self.fresh(op);
        self.nodes.push(pb::NodeProto {
            input: inputs.iter().map(|s| s.to_string()).collect(),
            output: vec![out.clone()],
            name: out.clone(),
            op_type: op.to_owned(),
            attribute: attributes,
            ..Default::default()
        });
        out
    }

    /// Declares a graph input of `shape` (f32) and returns its name.
    pub fn input(&mut self, name: &str, shape: &[usize]) -> String {
        self.inputs.push(value_info(name, shape));
        name.to_owned()
    }

    /// A constant tensor of `dims` holding `data` (row-major); returns its name.
    ///
    /// # Panics
    /// If `data.len()` is not the product of `dims`.
    pub fn constant(&mut self, dims: &[usize], data: Vec<f32>) -> String {
        let name = self.fresh("w");
        self.named_constant(&name, dims, data)
    }

    /// A constant tensor named `name` (e.g. a layer's `conv1.weight`); returns the name.
    ///
    /// # Panics
    /// If `data.len()` is not the product of `dims`.
    pub fn named_constant(&mut self, name: &str, dims: &[usize], data: Vec<f32>) -> String {
        assert_eq!(data.len(), dims.iter().product::<usize>(), "constant size");
        self.initializers.push(pb::TensorProto {
            name: name.to_owned(),
            dims: dims.iter().map(|&d| d as i64).collect(),
            data_type: FLOAT,
            raw_data: data.iter().flat_map(|v| v.to_le_bytes()).collect(),
            ..Default::default()
        });
        name.to_owned()
    }

    /// `x` under the name `name` (an `Identity` node): to give a graph output its name.
    pub fn rename_output(&mut self, x: &str, name: &str) -> String {
        self.nodes.push(pb::NodeProto {
            input: vec![x.to_owned()],
            output: vec![name.to_owned()],
            name: name.to_owned(),
            op_type: "Identity".into(),
            ..Default::default()
        });
        name.to_owned()
    }

    /// `Conv`: `x` `[n, c, h, w]` with `weight` `[k, c, kh, kw]` and `bias` `[k]`, square
    /// `stride` and symmetric `pad`.
    pub fn conv(&mut self, x: &str, weight: &str, bias: &str, stride: usize, pad: usize) -> String {
        let (s, p) = (stride as i64, pad as i64);
        self.node(
            "Conv",
            &[x, weight, bias],
            vec![ints("strides", &[s, s]), ints("pads", &[p, p, p, p])],
        )
    }

    /// `Conv` with `dilation` between the kernel's taps on both axes (ONNX `dilations`),
    /// otherwise as [`Graph::conv`].
    pub fn conv_dilated(
        &mut self,
        x: &str,
        weight: &str,
        bias: &str,
        stride: usize,
        pad: usize,
        dilation: usize,
    ) -> String {
        let (s, p, d) = (stride as i64, pad as i64, dilation as i64);
        self.node(
            "Conv",
            &[x, weight, bias],
            vec![
                ints("strides", &[s, s]),
                ints("pads", &[p, p, p, p]),
                ints("dilations", &[d, d]),
            ],
        )
    }

    /// `Relu`.
    pub fn relu(&mut self, x: &str) -> String {
        self.node("Relu", &[x], vec![])
    }

    /// `Tanh`.
    pub fn tanh(&mut self, x: &str) -> String {
        self.node("Tanh", &[x], vec![])
    }

    /// `Flatten` to `[n, rest]`.
    pub fn flatten(&mut self, x: &str) -> String {
        self.node("Flatten", &[x], vec![int("axis", 1)])
    }

    /// `Gemm`: `x · weightᵀ + bias`, `weight` `[out, in]` (a linear layer).
    pub fn linear(&mut self, x: &str, weight: &str, bias: &str) -> String {
        self.node("Gemm", &[x, weight, bias], vec![int("transB", 1)])
    }

    /// `Concat` along `axis`.
    pub fn concat(&mut self, xs: &[&str], axis: i64) -> String {
        self.node("Concat", xs, vec![int("axis", axis)])
    }

    /// Element-wise `Mul` (broadcasting).
    pub fn mul(&mut self, a: &str, b: &str) -> String {
        self.node("Mul", &[a, b], vec![])
    }

    /// Element-wise `Add` (broadcasting).
    pub fn add(&mut self, a: &str, b: &str) -> String {
        self.node("Add", &[a, b], vec![])
    }

    /// A constant `int64` tensor of `dims` (a shape or axes for `Expand`, `Reshape`);
    /// returns its name.
    ///
    /// # Panics
    /// If `data.len()` is not the product of `dims`.
    pub fn int64_constant(&mut self, dims: &[usize], data: Vec<i64>) -> String {
        assert_eq!(data.len(), dims.iter().product::<usize>(), "constant size");
        let name = self.fresh("shape");
        self.initializers.push(pb::TensorProto {
            name: name.clone(),
            dims: dims.iter().map(|&d| d as i64).collect(),
            data_type: INT64,
            raw_data: data.iter().flat_map(|v| v.to_le_bytes()).collect(),
            ..Default::default()
        });
        name
    }

    /// `Expand`: `x` broadcast to the shape held by the `int64` tensor `shape`.
    pub fn expand(&mut self, x: &str, shape: &str) -> String {
        self.node("Expand", &[x, shape], vec![])
    }

    /// `ReduceSum` over every axis, keeping them (opset 13: no `axes` input).
    pub fn reduce_sum(&mut self, x: &str) -> String {
        self.node("ReduceSum", &[x], vec![int("keepdims", 1)])
    }

    /// Element-wise `Div` (broadcasting).
    pub fn div(&mut self, a: &str, b: &str) -> String {
        self.node("Div", &[a, b], vec![])
    }

    /// Declares `x` a graph output of `shape`.
    pub fn output(&mut self, x: &str, shape: &[usize]) {
        self.outputs.push(value_info(x, shape));
    }

    /// The ONNX file's bytes.
    pub fn encode(self, name: &str, doc: &str) -> Vec<u8> {
        let model = pb::ModelProto {
            ir_version: IR_VERSION,
            opset_import: vec![pb::OperatorSetIdProto {
                domain: String::new(),
                version: OPSET,
            }],
            producer_name: "paracosm-experiments".into(),
            producer_version: env!("CARGO_PKG_VERSION").into(),
            doc_string: doc.to_owned(),
            graph: Some(pb::GraphProto {
                node: self.nodes,
                name: name.to_owned(),
                initializer: self.initializers,
                input: self.inputs,
                output: self.outputs,
                ..Default::default()
            }),
            ..Default::default()
        };
        model.encode_to_vec()
    }
}
