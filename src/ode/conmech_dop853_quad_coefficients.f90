!> The Dormand-Prince 8(5,3) pair (Hairer's DOP853) in quadruple precision (real128).
!!
!! Accuracy of the coefficients: Hairer's dop853.f prints them as decimals of about 30
!! significant digits (the fifth-order estimator's weights e of 28), while real128 carries
!! 34. Taken as printed, the tableau's consistency conditions fail by up to 6e-29 (the row
!! sums sum_j a(i, j) = c(i) in rows 9-12), sum b - 1 = 6.6e-30 and sum e = -4.6e-28 (the
!! defects of the zeroth-order conditions, measured with mpmath at 50 digits). Here the
!! nodes are exact (rationals and (6 -+ sqrt 6)/30), rows 3, 4, 6 and 7 are exact (Prince
!! and Dormand's construction: c3/4, 3 c3/4, ..., (118 +- 23 sqrt 6)/1024, -9/512), and the
!! first column (a(i, 1), b1, bh1, e1), which multiplies c1 = 0 and so enters only the
!! zeroth-order conditions, is computed in real128 from the others: the row sums, sum b = 1,
!! sum bh = 1 and sum e = 0 then hold to real128 round-off. The higher conditions keep the
!! printed decimals' defects, 2.3e-30 for sum b c - 1/2 down to 1.8e-31 for
!! sum b c^7 - 1/8 (terms of order h^2 and above). Measured on Kepler's problem over ten
!! periods (e = 0, 0.25, 0.5): the error follows the tolerance down to rtol 1e-30 and
!! reaches 1e-29 .. 4e-30 at rtol 1e-32, where the tableau taken as printed stalls at
!! 4e-28 .. 1.7e-27 with the same steps.
module conmech_dop853_quad_coefficients
    use, intrinsic :: iso_fortran_env, only: qp => real128
    implicit none
    private

    !> nodes: exact forms (rationals, and (6 -+ sqrt 6)/30 with c3 = 2/3 c4, c2 = 2/3 c3)
    real(qp), parameter, public :: sqrt6 = sqrt(6.0_qp)
    real(qp), parameter, public :: c4 = (6.0_qp - sqrt6)/30.0_qp, c5 = (6.0_qp + sqrt6)/30.0_qp
    real(qp), parameter, public :: c3 = 2.0_qp*c4/3.0_qp, c2 = 2.0_qp*c3/3.0_qp
    real(qp), parameter, public :: c6 = 1.0_qp/3.0_qp, c7 = 0.25_qp, c8 = 4.0_qp/13.0_qp
    real(qp), parameter, public :: c9 = 127.0_qp/195.0_qp, c10 = 0.6_qp, c11 = 6.0_qp/7.0_qp
    !> stages: Hairer's decimals, exact forms in rows 3, 4, 6, 7 (Prince and Dormand's
    !! construction); a(i, 1) from the row sum
    real(qp), parameter, public :: a2_1 = c2
    real(qp), parameter, public :: a3_2 = 3.0_qp*c3/4.0_qp
    real(qp), parameter, public :: a3_1 = c3 - a3_2
    real(qp), parameter, public :: a4_3 = 3.0_qp*c4/4.0_qp
    real(qp), parameter, public :: a4_1 = c4 - a4_3
    real(qp), parameter, public :: a5_3 = -8.84549479328286085344864962717e-1_qp
    real(qp), parameter, public :: a5_4 = 9.24834003261792003115737966543e-1_qp
    real(qp), parameter, public :: a5_1 = c5 - a5_3 - a5_4
    real(qp), parameter, public :: a6_4 = (16.0_qp + sqrt6)/108.0_qp
    real(qp), parameter, public :: a6_5 = (16.0_qp - sqrt6)/108.0_qp
    real(qp), parameter, public :: a6_1 = c6 - a6_4 - a6_5
    real(qp), parameter, public :: a7_4 = (118.0_qp + 23.0_qp*sqrt6)/1024.0_qp
    real(qp), parameter, public :: a7_5 = (118.0_qp - 23.0_qp*sqrt6)/1024.0_qp
    real(qp), parameter, public :: a7_6 = -9.0_qp/512.0_qp
    real(qp), parameter, public :: a7_1 = c7 - a7_4 - a7_5 - a7_6
    real(qp), parameter, public :: a8_4 = 1.70383925712239993810214054705e-1_qp
    real(qp), parameter, public :: a8_5 = 1.07262030446373284651809199168e-1_qp
    real(qp), parameter, public :: a8_6 = -1.53194377486244017527936158236e-2_qp
    real(qp), parameter, public :: a8_7 = 8.27378916381402288758473766002e-3_qp
    real(qp), parameter, public :: a8_1 = c8 - a8_4 - a8_5 - a8_6 - a8_7
    real(qp), parameter, public :: a9_4 = -3.36089262944694129406857109825_qp
    real(qp), parameter, public :: a9_5 = -8.68219346841726006818189891453e-1_qp
    real(qp), parameter, public :: a9_6 = 2.75920996994467083049415600797e1_qp
    real(qp), parameter, public :: a9_7 = 2.01540675504778934086186788979e1_qp
    real(qp), parameter, public :: a9_8 = -4.34898841810699588477366255144e1_qp
    real(qp), parameter, public :: a9_1 = c9 - a9_4 - a9_5 - a9_6 - a9_7 - a9_8
    real(qp), parameter, public :: a10_4 = -2.48811461997166764192642586468_qp
    real(qp), parameter, public :: a10_5 = -5.90290826836842996371446475743e-1_qp
    real(qp), parameter, public :: a10_6 = 2.12300514481811942347288949897e1_qp
    real(qp), parameter, public :: a10_7 = 1.52792336328824235832596922938e1_qp
    real(qp), parameter, public :: a10_8 = -3.32882109689848629194453265587e1_qp
    real(qp), parameter, public :: a10_9 = -2.03312017085086261358222928593e-2_qp
    real(qp), parameter, public :: a10_1 = c10 - a10_4 - a10_5 - a10_6 - a10_7 - a10_8 - a10_9
    real(qp), parameter, public :: a11_4 = 5.18637242884406370830023853209_qp
    real(qp), parameter, public :: a11_5 = 1.09143734899672957818500254654_qp
    real(qp), parameter, public :: a11_6 = -8.14978701074692612513997267357_qp
    real(qp), parameter, public :: a11_7 = -1.85200656599969598641566180701e1_qp
    real(qp), parameter, public :: a11_8 = 2.27394870993505042818970056734e1_qp
    real(qp), parameter, public :: a11_9 = 2.49360555267965238987089396762_qp
    real(qp), parameter, public :: a11_10 = -3.0467644718982195003823669022_qp
    real(qp), parameter, public :: a11_1 = c11 - a11_4 - a11_5 - a11_6 - a11_7 - a11_8 - a11_9 &
                                             - a11_10
    real(qp), parameter, public :: a12_4 = -1.05344954667372501984066689879e1_qp
    real(qp), parameter, public :: a12_5 = -2.00087205822486249909675718444_qp
    real(qp), parameter, public :: a12_6 = -1.79589318631187989172765950534e1_qp
    real(qp), parameter, public :: a12_7 = 2.79488845294199600508499808837e1_qp
    real(qp), parameter, public :: a12_8 = -2.85899827713502369474065508674_qp
    real(qp), parameter, public :: a12_9 = -8.87285693353062954433549289258_qp
    real(qp), parameter, public :: a12_10 = 1.23605671757943030647266201528e1_qp
    real(qp), parameter, public :: a12_11 = 6.43392746015763530355970484046e-1_qp
    real(qp), parameter, public :: a12_1 = 1.0_qp - a12_4 - a12_5 - a12_6 - a12_7 - a12_8 - a12_9 &
                                              - a12_10 - a12_11
    real(qp), parameter, public :: b6 = 4.45031289275240888144113950566_qp
    real(qp), parameter, public :: b7 = 1.89151789931450038304281599044_qp
    real(qp), parameter, public :: b8 = -5.8012039600105847814672114227_qp
    real(qp), parameter, public :: b9 = 3.1116436695781989440891606237e-1_qp
    real(qp), parameter, public :: b10 = -1.52160949662516078556178806805e-1_qp
    real(qp), parameter, public :: b11 = 2.01365400804030348374776537501e-1_qp
    real(qp), parameter, public :: b12 = 4.47106157277725905176885569043e-2_qp
    real(qp), parameter, public :: b1 = 1.0_qp - b6 - b7 - b8 - b9 - b10 - b11 - b12
    !> third-order estimator weights (exact: 31/127 + 12675/17272 + 3/136 = 1)
    real(qp), parameter, public :: bh9 = 12675.0_qp/17272.0_qp
    real(qp), parameter, public :: bh12 = 3.0_qp/136.0_qp
    real(qp), parameter, public :: bh1 = 31.0_qp/127.0_qp
    !> fifth-order estimator weights (28 digits); e1 from sum e = 0
    real(qp), parameter, public :: e6 = -0.1225156446376204440720569753e1_qp
    real(qp), parameter, public :: e7 = -0.4957589496572501915214079952_qp
    real(qp), parameter, public :: e8 = 0.1664377182454986536961530415e1_qp
    real(qp), parameter, public :: e9 = -0.3503288487499736816886487290_qp
    real(qp), parameter, public :: e10 = 0.3341791187130174790297318841_qp
    real(qp), parameter, public :: e11 = 0.8192320648511571246570742613e-1_qp
    real(qp), parameter, public :: e12 = -0.2235530786388629525884427845e-1_qp
    real(qp), parameter, public :: e1 = -(e6 + e7 + e8 + e9 + e10 + e11 + e12)

end module conmech_dop853_quad_coefficients
