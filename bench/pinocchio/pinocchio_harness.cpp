// Pinocchio's aba or computeABADerivatives `reps` times on a model rebuilt from the joint
// placements and inertias that pinocchio's own URDF parser produced (dumped from Python
// by bench_pinocchio.py: the wheel ships no urdfdom headers). Same harness as
// conmech_harness.c: callgrind instructions per call, or the wall time of the loop.
// Usage: pinocchio_harness MODEL.txt REPS WHICH(0 aba, 1 computeABADerivatives)
#include <pinocchio/multibody.hpp>
#include <pinocchio/algorithm/rnea.hpp>
#include <pinocchio/algorithm/aba.hpp>
#include <pinocchio/algorithm/aba-derivatives.hpp>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
int main(int argc, char **argv) {
    if (argc < 4) return 2;
    pinocchio::Model model;
    FILE *f = fopen(argv[1], "r");
    if (!f) return 1;
    int nj;
    if (fscanf(f, "%d", &nj) != 1) return 1;
    for (int j = 0; j < nj; j++) {
        char kind[16];
        double x[26];
        if (fscanf(f, "%15s", kind) != 1) return 1;
        for (int k = 0; k < 26; k++) if (fscanf(f, "%lf", &x[k]) != 1) return 1;
        Eigen::Matrix3d R, I;
        Eigen::Vector3d p, c;
        for (int r = 0; r < 3; r++)
            for (int s = 0; s < 3; s++) { R(r, s) = x[1 + 3 * r + s]; I(r, s) = x[17 + 3 * r + s]; }
        p << x[10], x[11], x[12];
        c << x[14], x[15], x[16];
        std::string k(kind);
        pinocchio::JointIndex parent = (pinocchio::JointIndex)x[0];
        pinocchio::SE3 M(R, p);
        pinocchio::JointIndex id;
        std::string name = "j" + std::to_string(j + 1);
        if (k == "RX") id = model.addJoint(parent, pinocchio::JointModelRX(), M, name);
        else if (k == "RY") id = model.addJoint(parent, pinocchio::JointModelRY(), M, name);
        else if (k == "RZ") id = model.addJoint(parent, pinocchio::JointModelRZ(), M, name);
        else if (k == "PX") id = model.addJoint(parent, pinocchio::JointModelPX(), M, name);
        else if (k == "PY") id = model.addJoint(parent, pinocchio::JointModelPY(), M, name);
        else if (k == "PZ") id = model.addJoint(parent, pinocchio::JointModelPZ(), M, name);
        else { fprintf(stderr, "joint kind %s not supported by the harness\n", kind); return 1; }
        model.appendBodyToJoint(id, pinocchio::Inertia(x[13], c, I), pinocchio::SE3::Identity());
    }
    fclose(f);
    pinocchio::Data data(model);
    int reps = atoi(argv[2]), which = atoi(argv[3]);
    Eigen::VectorXd q(model.nq), v(model.nv), tau = Eigen::VectorXd::Zero(model.nv);
    for (int i = 0; i < model.nq; i++) q[i] = 0.3 + 0.1 * i;
    for (int i = 0; i < model.nv; i++) v[i] = -0.2 + 0.05 * i;
    double s = 0;
    auto t0 = std::chrono::steady_clock::now();
    for (int r = 0; r < reps; r++) {
        q[0] += 1e-9;
        if (which == 0) { pinocchio::aba(model, data, q, v, tau); s += data.ddq[model.nv - 1]; }
        else { pinocchio::computeABADerivatives(model, data, q, v, tau); s += data.ddq_dq(0, 0); }
    }
    auto t1 = std::chrono::steady_clock::now();
    printf("%.17g %.9f\n", s, std::chrono::duration<double>(t1 - t0).count());
    return 0;
}
