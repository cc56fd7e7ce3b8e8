!> Fixed-step DOP853 kernels for Hill's variation orbit (conmech_hill_orbit): the state
!! with three columns of its state transition matrix (16 equations), and the state alone (4
!! equations), over [0, t1] in n equal steps, with the right-hand sides written out and the
!! Dormand-Prince 8th-order coefficients as constants (the tableau of conmech_rk_tableaus,
!! `dop853_tableau`, stages 1-12 and the weights of the propagated solution = row 13).
!!
!! Equations (Hill's problem, kappa/r potential, rotating frame):
!! x'' = 2 m y' + F_x, y'' = -2 m x' + F_y, F = kappa/r + (3/2) m^2 x^2; the columns are the
!! variations of the initial state along e1 (x0), e3 (x0') and e4 (y0' = v0): the two
!! unknowns of symmetric shooting and the transverse odd perturbation. The fourth column
!! (e2, y0) follows from the flow: A f(y0) = f(y(t1)) (conmech_hill_orbit).
!!
!! Thread safety: pure procedures, no saved state.
module conmech_hill_kernel
    use conmech_kinds, only: dp
    implicit none
    private
    public :: hill_kernel_var, hill_kernel_state, hill_var_rhs

    real(dp), parameter :: a2_1 = 5.26001519587677318785587544488e-2_dp
    real(dp), parameter :: a3_1 = 1.97250569845378994544595329183e-2_dp
    real(dp), parameter :: a3_2 = 5.91751709536136983633785987549e-2_dp
    real(dp), parameter :: a4_1 = 2.95875854768068491816892993775e-2_dp
    real(dp), parameter :: a4_3 = 8.87627564304205475450678981324e-2_dp
    real(dp), parameter :: a5_1 = 2.41365134159266685502369798665e-1_dp
    real(dp), parameter :: a5_3 = -8.84549479328286085344864962717e-1_dp
    real(dp), parameter :: a5_4 = 9.24834003261792003115737966543e-1_dp
    real(dp), parameter :: a6_1 = 3.7037037037037037037037037037e-2_dp
    real(dp), parameter :: a6_4 = 1.70828608729473871279604482173e-1_dp
    real(dp), parameter :: a6_5 = 1.25467687566822425016691814123e-1_dp
    real(dp), parameter :: a7_1 = 3.7109375e-2_dp
    real(dp), parameter :: a7_4 = 1.70252211019544039314978060272e-1_dp
    real(dp), parameter :: a7_5 = 6.02165389804559606850219397283e-2_dp
    real(dp), parameter :: a7_6 = -1.7578125e-2_dp
    real(dp), parameter :: a8_1 = 3.70920001185047927108779319836e-2_dp
    real(dp), parameter :: a8_4 = 1.70383925712239993810214054705e-1_dp
    real(dp), parameter :: a8_5 = 1.07262030446373284651809199168e-1_dp
    real(dp), parameter :: a8_6 = -1.53194377486244017527936158236e-2_dp
    real(dp), parameter :: a8_7 = 8.27378916381402288758473766002e-3_dp
    real(dp), parameter :: a9_1 = 6.24110958716075717114429577812e-1_dp
    real(dp), parameter :: a9_4 = -3.36089262944694129406857109825_dp
    real(dp), parameter :: a9_5 = -8.68219346841726006818189891453e-1_dp
    real(dp), parameter :: a9_6 = 2.75920996994467083049415600797e1_dp
    real(dp), parameter :: a9_7 = 2.01540675504778934086186788979e1_dp
    real(dp), parameter :: a9_8 = -4.34898841810699588477366255144e1_dp
    real(dp), parameter :: a10_1 = 4.77662536438264365890433908527e-1_dp
    real(dp), parameter :: a10_4 = -2.48811461997166764192642586468_dp
    real(dp), parameter :: a10_5 = -5.90290826836842996371446475743e-1_dp
    real(dp), parameter :: a10_6 = 2.12300514481811942347288949897e1_dp
    real(dp), parameter :: a10_7 = 1.52792336328824235832596922938e1_dp
    real(dp), parameter :: a10_8 = -3.32882109689848629194453265587e1_dp
    real(dp), parameter :: a10_9 = -2.03312017085086261358222928593e-2_dp
    real(dp), parameter :: a11_1 = -9.3714243008598732571704021658e-1_dp
    real(dp), parameter :: a11_4 = 5.18637242884406370830023853209_dp
    real(dp), parameter :: a11_5 = 1.09143734899672957818500254654_dp
    real(dp), parameter :: a11_6 = -8.14978701074692612513997267357_dp
    real(dp), parameter :: a11_7 = -1.85200656599969598641566180701e1_dp
    real(dp), parameter :: a11_8 = 2.27394870993505042818970056734e1_dp
    real(dp), parameter :: a11_9 = 2.49360555267965238987089396762_dp
    real(dp), parameter :: a11_10 = -3.0467644718982195003823669022_dp
    real(dp), parameter :: a12_1 = 2.27331014751653820792359768449_dp
    real(dp), parameter :: a12_4 = -1.05344954667372501984066689879e1_dp
    real(dp), parameter :: a12_5 = -2.00087205822486249909675718444_dp
    real(dp), parameter :: a12_6 = -1.79589318631187989172765950534e1_dp
    real(dp), parameter :: a12_7 = 2.79488845294199600508499808837e1_dp
    real(dp), parameter :: a12_8 = -2.85899827713502369474065508674_dp
    real(dp), parameter :: a12_9 = -8.87285693353062954433549289258_dp
    real(dp), parameter :: a12_10 = 1.23605671757943030647266201528e1_dp
    real(dp), parameter :: a12_11 = 6.43392746015763530355970484046e-1_dp
    real(dp), parameter :: b1 = 5.42937341165687622380535766363e-2_dp
    real(dp), parameter :: b6 = 4.45031289275240888144113950566_dp
    real(dp), parameter :: b7 = 1.89151789931450038304281599044_dp
    real(dp), parameter :: b8 = -5.8012039600105847814672114227_dp
    real(dp), parameter :: b9 = 3.1116436695781989440891606237e-1_dp
    real(dp), parameter :: b10 = -1.52160949662516078556178806805e-1_dp
    real(dp), parameter :: b11 = 2.01365400804030348374776537501e-1_dp
    real(dp), parameter :: b12 = 4.47106157277725905176885569043e-2_dp

contains

    !> dz for z = [x, y, x', y', c1(4), ..., cj(4)], nz = 4 + 4 j >= 8 (c: columns of the
    !! STM; conmech_hill_orbit integrates all four, the kernel three).
    pure subroutine hill_var_rhs(m, kappa, nz, z, dz)
        integer, intent(in) :: nz
        real(dp), intent(in) :: m, kappa, z(nz)
        real(dp), intent(out) :: dz(nz)
        real(dp) :: x, y, ir, ir3, k3, fxx, fxy, fyy, tm, m3
        integer :: o
        x = z(1)
        y = z(2)
        ir = 1.0_dp/sqrt(x*x + y*y)
        ir3 = kappa*ir*ir*ir
        tm = 2.0_dp*m
        m3 = 3.0_dp*m*m
        dz(1) = z(3)
        dz(2) = z(4)
        dz(3) = tm*z(4) - x*ir3 + m3*x
        dz(4) = -tm*z(3) - y*ir3
        k3 = 3.0_dp*ir3*ir*ir
        fxx = k3*x*x - ir3 + m3
        fxy = k3*x*y
        fyy = k3*y*y - ir3
        do o = 4, nz - 4, 4
            dz(o + 1) = z(o + 3)
            dz(o + 2) = z(o + 4)
            dz(o + 3) = fxx*z(o + 1) + fxy*z(o + 2) + tm*z(o + 4)
            dz(o + 4) = fxy*z(o + 1) + fyy*z(o + 2) - tm*z(o + 3)
        end do
    end subroutine hill_var_rhs

    !> ds for the state s = [x, y, x', y'].
    pure subroutine state_rhs(m, kappa, s, ds)
        real(dp), intent(in) :: m, kappa, s(4)
        real(dp), intent(out) :: ds(4)
        real(dp) :: ir, ir3
        ir = 1.0_dp/sqrt(s(1)*s(1) + s(2)*s(2))
        ir3 = kappa*ir*ir*ir
        ds(1) = s(3)
        ds(2) = s(4)
        ds(3) = 2.0_dp*m*s(4) - s(1)*ir3 + 3.0_dp*m*m*s(1)
        ds(4) = -2.0_dp*m*s(3) - s(2)*ir3
    end subroutine state_rhs

    !> The state and three STM columns, z = [x, y, x', y', A e1, A e3, A e4], from t = 0 to
    !! t1 in n DOP853 steps (z holds the initial values on entry). nfev += 12 n.
    pure subroutine hill_kernel_var(m, kappa, t1, n, z, nfev)
        integer, parameter :: nz = 16
        real(dp), intent(in) :: m, kappa, t1
        integer, intent(in) :: n
        real(dp), intent(inout) :: z(nz)
        integer, intent(inout) :: nfev
        include "conmech_hill_kernel_body.inc"
    contains
        pure subroutine rhs_of(s, ds)
            real(dp), intent(in) :: s(nz)
            real(dp), intent(out) :: ds(nz)
            call hill_var_rhs(m, kappa, nz, s, ds)
        end subroutine rhs_of
    end subroutine hill_kernel_var

    !> The state s = [x, y, x', y'] from t = 0 to t1 in n DOP853 steps. nfev += 12 n.
    pure subroutine hill_kernel_state(m, kappa, t1, n, z, nfev)
        integer, parameter :: nz = 4
        real(dp), intent(in) :: m, kappa, t1
        integer, intent(in) :: n
        real(dp), intent(inout) :: z(nz)
        integer, intent(inout) :: nfev
        include "conmech_hill_kernel_body.inc"
    contains
        pure subroutine rhs_of(s, ds)
            real(dp), intent(in) :: s(nz)
            real(dp), intent(out) :: ds(nz)
            call state_rhs(m, kappa, s, ds)
        end subroutine rhs_of
    end subroutine hill_kernel_state

end module conmech_hill_kernel
