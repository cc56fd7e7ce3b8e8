!> The name of an integer code from a table of codes and names: the one lookup behind the
!! `*_name` functions of the stability types (special-point kinds, classifications,
!! orbit methods), so each of them is its table alone.
module conmech_code_names
    implicit none
    private

    public :: code_name

contains

    !> names(k) (trailing blanks trimmed) for the first k with codes(k) == code, otherwise
    !! `other`.
    pure function code_name(code, codes, names, other) result(s)
        integer, intent(in) :: code
        integer, intent(in) :: codes(:)
        character(len=*), intent(in) :: names(:)
        character(len=*), intent(in) :: other
        character(len=:), allocatable :: s
        integer :: k
        do k = 1, min(size(codes), size(names))
            if (codes(k) == code) then
                s = trim(names(k))
                return
            end if
        end do
        s = other
    end function code_name

end module conmech_code_names
