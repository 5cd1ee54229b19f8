# Equations of motion of `examples/double_pendulum.lsd`, written by lsdc for Maple:
#   M(p) . q' = S(p, q) + F(p, q, t) + Delta^T . Lambda,   Delta(p) . q' + Delta_bias(p, q) = 0
# p the positions, q their rates, q' the rates' derivatives, Lambda the constraints' multipliers.
# Derived by the thesis's Lagrange form (free bodies' Newton-Euler blocks premultiplied by Psi^T).

# Positions.
#   shoulder_q: coordinate `q` of join `shoulder`
#   elbow_q: coordinate `q` of join `elbow`

# Rates.
#   shoulder_q_dot: rate of the coordinate `q` of join `shoulder`
#   elbow_q_dot: rate of the coordinate `q` of join `elbow`

# Time.
#   t

# Subexpressions used more than once.
x0 := sin(elbow_q);
x1 := -x0;
x2 := sin(shoulder_q);
x3 := cos(elbow_q);
x4 := cos(shoulder_q);
x5 := x4 * x3 + x2 * x1;
x6 := x5 * 0.32000000000000006;
x7 := -x4;
x8 := x4 * x1 + -x2 * x3;
x9 := x8 * (-0.32000000000000006);
x10 := x5 * (-0.32000000000000006);
x11 := x2 * x9;
x12 := shoulder_q_dot * (shoulder_q_dot * x2);
x13 := shoulder_q_dot + elbow_q_dot;
x14 := shoulder_q_dot * (-(shoulder_q_dot * x7));
x15 := -(x14 * x9 - -x12 * x10);
x16 := x8 * (-0.4);
x17 := -7.848000000000001 * x16;
x18 := x2 * 0.5;
x19 := shoulder_q_dot * x1;
x20 := elbow_q_dot * x19;
x21 := 0.8 * x19;
x22 := shoulder_q_dot * x3;
x23 := 0.8 * x22 + x13 * 0.32000000000000006;
x24 := x22 * x21 - x19 * x23 + x16 * 7.848000000000001;
x25 := -x24;
x26 := x25 / 0.17066666666666672;
x27 := 0.32000000000000006 * x26 + ((x2 * x3 + x4 * x0) * 7.848000000000001 - x13 * x21 + x20 * 0.19999999999999996);
x28 := 0.0 * x26;
x29 := 0.0 * x28;
x30 := elbow_q_dot * x22;
x31 := x28 + (x13 * x23 + x5 * 7.848000000000001 + -0.8 * x30);
x32 := x1 * x31 + (x29 + x3 * x27);
x33 := 0.0 * x31 + (x28 + 0.0 * x27);
x34 := 0.0 * x33;
x35 := x3 * x31 + (x29 + x0 * x27);
x36 := 0.0 * x35;
x37 := x24 + 0.17066666666666672 * x26;
x38 := x3 * x28;
x39 := 0.0 * x37;
x40 := -(0.0 * (x38 + (x39 + x0 * x28) + (0.0 * x32 + x34)) + (0.0 * (x1 * x28 + (x39 + x38) + (x36 - x33)) + (x18 * 9.81 + (x29 + (x37 + x29) + (x32 + x36)) + (0.0 * (shoulder_q_dot * (shoulder_q_dot * 0.5) + x4 * 9.81 + x35) + (x34 + 0.0 * (x2 * 9.81 + x32)))))) / (0.3333333333333333 + (x3 * (x3 * 0.19999999999999996) + x1 * (x0 * (-0.8))));
x41 := 0.0 * x40;
x42 := 0.0 * x41;
x43 := x40 + x42;
x44 := x41 + x43;
x45 := x41 + (x41 + x42);
x46 := 0.0 * x45;
x47 := x3 * x41;

M := Matrix(2, 2, shape = symmetric);
S := Vector(2);
F := Vector(2);
Delta := Matrix(0, 2);
Delta_bias := Vector(0);
accelerations := Vector(2);
M[1, 1] := 0.3333333333333333 + (0.17066666666666672 + (x11 - x4 * x10) + (x2 * (x9 + x2 * 0.8) - x7 * (x4 * 0.8 + x6)));
M[1, 2] := 0.17066666666666672 + (x11 - x7 * x6);
M[2, 2] := 0.17066666666666672;
S[1] := x15 + (x2 * (x14 * (-0.8) - x13 * (-(x13 * x10))) - x7 * (x13 * (x13 * x9) + x12 * 0.8));
S[2] := x15;
F[1] := x18 * (-9.81) + (x17 + x2 * (-7.848000000000001));
F[2] := x17;
accelerations[1] := x40;
accelerations[2] := (x25 - (0.0 * (x47 + (x41 + x1 * x41)) + (0.0 * (x0 * x41 + (x41 + x47)) + (0.17066666666666672 * (x42 + x43) + (0.0 * (x3 * x45 + (x46 + x1 * x44) - x30) + (0.0 * (x46 + (x45 + 0.0 * x44)) + 0.32000000000000006 * (x20 + (x0 * x45 + (x46 + x3 * x44))))))))) / 0.17066666666666672;
