!> The constants of Radau IIA of order 5 (three stages) and of RADAU5's iteration control
!! (Hairer & Wanner, Solving ODEs II, section IV.8): the nodes, the eigenvalues of the
!! inverse Radau matrix and its transformation T, T^{-1}, the error-estimate weights, the
!! Newton limits and the step-keeping window. Parameters only (no state).
module conmech_radau_coefficients
    use conmech_kinds, only: dp
    implicit none
    private

    public :: C1, C2, DD1, DD2, DD3, GAM0, ALPH, BETA
    public :: T11, T12, T13, T21, T22, T23, T31
    public :: TI11, TI12, TI13, TI21, TI22, TI23, TI31, TI32, TI33
    public :: NIT, THET, QUOT1, QUOT2

    real(dp), parameter :: SQ6 = sqrt(6.0_dp)
    !> the nodes c1, c2 (c3 = 1)
    real(dp), parameter :: C1 = (4.0_dp - SQ6)/10.0_dp, C2 = (4.0_dp + SQ6)/10.0_dp
    !> the weights of the error estimate (RADAU5's dd1..dd3)
    real(dp), parameter :: DD1 = -(13.0_dp + 7.0_dp*SQ6)/3.0_dp
    real(dp), parameter :: DD2 = (-13.0_dp + 7.0_dp*SQ6)/3.0_dp
    real(dp), parameter :: DD3 = -1.0_dp/3.0_dp
    !> eigenvalues of the inverse Radau matrix: gamma (real), alpha +- i beta
    real(dp), parameter :: GAM0 = 3.6378342527444957322_dp
    real(dp), parameter :: ALPH = 2.6810828736277521339_dp
    real(dp), parameter :: BETA = 3.0504301992474105694_dp
    !> T^{-1} A^{-1} T = diag(gamma, [[alpha, -beta], [beta, alpha]]) (Hairer's T, TI)
    real(dp), parameter :: T11 = 9.1232394870892942792e-02_dp
    real(dp), parameter :: T12 = -0.14125529502095420843_dp
    real(dp), parameter :: T13 = -3.0029194105147424492e-02_dp
    real(dp), parameter :: T21 = 0.24171793270710701896_dp
    real(dp), parameter :: T22 = 0.20412935229379993199_dp
    real(dp), parameter :: T23 = 0.38294211275726193779_dp
    real(dp), parameter :: T31 = 0.96604818261509293619_dp
    real(dp), parameter :: TI11 = 4.3255798900631553510_dp
    real(dp), parameter :: TI12 = 0.33919925181580986954_dp
    real(dp), parameter :: TI13 = 0.54177053993587487119_dp
    real(dp), parameter :: TI21 = -4.1787185915519047273_dp
    real(dp), parameter :: TI22 = -0.32768282076106238708_dp
    real(dp), parameter :: TI23 = 0.47662355450055045196_dp
    real(dp), parameter :: TI31 = -0.50287263494578687595_dp
    real(dp), parameter :: TI32 = 2.5719269498556054292_dp
    real(dp), parameter :: TI33 = -0.59603920482822492497_dp
    integer, parameter :: NIT = 7                 !! Newton iterations per step at most
    real(dp), parameter :: THET = 0.001_dp        !! Jacobian reuse threshold
    !> after an accepted step, h and the LU are kept when the proposed ratio is below QUOT2
    !! and the Jacobian is not refreshed (SciPy's rule; RADAU5's default window is [1, 1.2])
    real(dp), parameter :: QUOT1 = 0.0_dp, QUOT2 = 1.2_dp

end module conmech_radau_coefficients
